"""Creating a SAPIEN scene, with one clear sentence when no Vulkan device exists."""

from __future__ import annotations

import sapien

from bt_grasp.errors import RenderDeviceError

NO_DEVICE_HELP = (
    "no Vulkan rendering device found: SAPIEN needs a GPU Vulkan driver or Mesa's software driver "
    "lavapipe >= 24.3; run `make setup` (it installs mesa-vulkan-drivers) and try again"
)


def create_scene() -> sapien.Scene:
    """A new SAPIEN scene with physics and rendering; RenderDeviceError if rendering is impossible."""
    try:
        return sapien.Scene()
    except RuntimeError as exc:
        text = str(exc).lower()
        if "device" in text or "vulkan" in text or "vk" in text:
            raise RenderDeviceError(NO_DEVICE_HELP) from exc
        raise
