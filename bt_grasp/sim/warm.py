"""Keeping SAPIEN's renderer warm in a long-lived process (campaign workers).

SAPIEN creates its renderer's shared resources (compiled pipelines, the BRDF lookup table its default
shaders sample) on the first picture any camera takes, and frees them when the last scene is gone. On
lavapipe that first picture costs 3.5-7 s of CPU. A process that builds one world per episode would pay it
again every episode; holding one tiny scene with a 16x16 camera alive keeps those resources, and a new
world's first picture then costs ~0.1 s (measured: docs/campaigns.md).
"""

from __future__ import annotations

import sapien

from bt_grasp.sim.device import create_scene


class RendererKeepalive:
    """Holds a minimal scene whose camera has taken one picture, for as long as this object lives."""

    def __init__(self) -> None:
        self._scene = create_scene()
        self._camera = sapien.render.RenderCameraComponent(16, 16)
        entity = sapien.Entity()
        entity.set_name("renderer_keepalive")
        entity.add_component(self._camera)
        self._scene.add_entity(entity)
        self._scene.update_render()
        self._camera.take_picture()
        self._camera.get_picture("Color")
