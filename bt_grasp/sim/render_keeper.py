"""Keeps the renderer's one-time set-up alive for the whole process, so every new world's first picture is cheap.

On a CPU Vulkan driver (lavapipe) the first picture taken in a process costs seconds: the renderer's one-time
resource set-up runs as shaders that lavapipe compiles (docs/campaigns.md says how this was measured). It is
kept while any SAPIEN scene lives; a tiny scene with a 16x16 camera that has taken one picture keeps it, and then
a world built afresh for each episode pays about 0.1 s for its first picture.

Why fresh worlds and not one world reset between episodes: a reset world keeps PhysX's internal state (its
contact pairs' order among others), and the same episode run again in a reset world gave a different tick
stream on some runs (the pick-with-recovery seed-0 episode: A, A, B, A, B). Worlds built afresh beside this
keeper gave the fresh process's tick stream every time (tests/episode/test_warm_world.py).
"""

from __future__ import annotations

import threading

import sapien

from bt_grasp.sim.device import create_scene

_lock = threading.Lock()
_kept: tuple[sapien.Scene, object] | None = None


def keep_renderer_warm() -> None:
    """Pay the renderer's one-time set-up now (once per process) and keep it until the process ends."""
    global _kept
    with _lock:
        if _kept is not None:
            return
        scene = create_scene()
        camera = scene.add_camera("render_keeper", 16, 16, 1.0, 0.01, 10.0)
        scene.update_render()
        camera.take_picture()
        _kept = (scene, camera)
