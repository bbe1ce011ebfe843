"""Keeps the renderer's one-time set-up alive for the whole process, so every new world's first picture is cheap.

On a CPU Vulkan driver (lavapipe) the first picture taken in a process pays the renderer's one-time set-up:
with SAPIEN's own shader packs seconds (mostly the BRDF lookup table of image-based lighting), with bt_grasp's
pack (``bt_grasp.sim.shader_pack``, docs/rendering.md) a few tenths of a second. It is kept while any SAPIEN
scene lives; a tiny scene with a 16x16 camera that has taken one picture keeps it, and then a world built afresh
for each episode pays less for its first picture.

Why fresh worlds and not one world reset between episodes: a reset world keeps PhysX's internal state (its
contact pairs' order among others), and the same episode run again in a reset world gave a different tick
stream on some runs (the pick-with-recovery seed-0 episode: A, A, B, A, B). Worlds built afresh beside this
keeper gave the fresh process's tick stream every time (tests/episode/test_warm_world.py).
"""

from __future__ import annotations

import threading

import sapien

from bt_grasp.sim.device import create_scene
from bt_grasp.sim.shader_pack import SHADER_DIR

_lock = threading.Lock()
_kept: tuple[sapien.Scene, object] | None = None


def keep_renderer_warm() -> None:
    """Pay the renderer's one-time set-up now (once per process) and keep it until the process ends."""
    global _kept
    with _lock:
        if _kept is not None:
            return
        scene = create_scene()
        camera = sapien.render.RenderCameraComponent(16, 16, SHADER_DIR)
        entity = sapien.Entity()
        entity.set_name("render_keeper")
        entity.add_component(camera)
        scene.add_entity(entity)
        scene.update_render()
        camera.take_picture()
        _kept = (scene, camera)
