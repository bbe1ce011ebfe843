"""bt_grasp's own camera shader pack (``bt_grasp/sim/shaders/``, docs/rendering.md).

SAPIEN's "default" and "minimal" packs bind a BRDF lookup table for image-based lighting, which svulkan2 builds
with a compute pass at a process's first picture: seconds on a CPU Vulkan driver (lavapipe). The scenes set no
environment map, so that lighting adds nothing to the picture. This pack draws what the pipeline and the log
use (Color, Position) with the lights the scenes use (ambient, directional, point, their shadows) and no
image-based lighting: the same pictures (tests/sim/test_shader_pack.py) from a first picture in a fraction of a
second.
"""

from __future__ import annotations

from pathlib import Path

#: the pack's folder, given to every camera bt_grasp makes (``RenderCameraComponent(w, h, SHADER_DIR)``)
SHADER_DIR = str(Path(__file__).resolve().parent / "shaders")
