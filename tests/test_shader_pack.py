"""bt_grasp's shader pack (bt_grasp/sim/shaders, docs/rendering.md) draws the pictures SAPIEN's default pack drew.

Each shipped scene is rendered twice in one process, from one place: through the pipeline's camera (the pack)
and through a reference camera with SAPIEN's "default" pack. Colour must agree within 2/255 per pixel and
channel, depth (from the Position picture) to the bit; the log camera's 8-bit frames likewise.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import sapien
from numpy.typing import NDArray

from bt_grasp.sim.shader_pack import SHADER_DIR
from bt_grasp.sim.world import World

_SAPIEN_DEFAULT = os.path.join(os.path.dirname(sapien.__file__), "vulkan_shader", "default")


def test_the_pack_binds_no_image_based_lighting() -> None:
    """No environment map and no BRDF lookup table: the bindings whose set-up cost seconds at the first picture."""
    sources = {p.name: p.read_text() for p in Path(SHADER_DIR).iterdir()}
    assert {"gbuffer.vert", "gbuffer.frag", "composite.vert", "composite0.frag", "shadow.vert"} <= set(sources)
    for name, text in sources.items():
        assert "samplerBRDFLUT" not in text and "samplerEnvironment" not in text, name


def _reference_pictures(world: World) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Colour and depth as the pipeline's camera computes them, through a camera with SAPIEN's default pack at the
    same place with the same intrinsics."""
    pipeline = world.camera._component
    reference = sapien.render.RenderCameraComponent(pipeline.width, pipeline.height, _SAPIEN_DEFAULT)
    reference.set_fovy(pipeline.fovy, compute_x=True)
    reference.near, reference.far = pipeline.near, pipeline.far
    reference.set_local_pose(pipeline.get_local_pose())
    pipeline.entity.add_component(reference)
    world.scene.update_render()
    reference.take_picture()
    color = np.clip(np.round(reference.get_picture("Color")[..., :3] * 255.0), 0, 255).astype(np.uint8)
    position = reference.get_picture("Position")
    depth = (-position[..., 2]).astype(np.float32)
    depth[position[..., 3] >= 1.0] = 0.0
    depth[depth < 0] = 0.0
    return color, depth


@pytest.mark.sim
@pytest.mark.parametrize("scene", ["tabletop", "clutter", "eye_in_hand", "conveyor"])
def test_the_pictures_stay_what_sapiens_default_pack_drew(repo_root: Path, scene: str) -> None:
    world = World.from_file(repo_root / "scenes" / f"{scene}.yaml", seed=3)
    world.step(50)  # objects settled on their supports, belts moving
    color, depth = world.camera.render_true()
    logged = world.camera.render_color(fast_shader=True)
    ref_color, ref_depth = _reference_pictures(world)

    assert (depth > 0).mean() > 0.9  # the scene is in view, not an empty picture
    np.testing.assert_array_equal(depth, ref_depth)
    for picture in (color, logged):
        difference = np.abs(picture.astype(np.int16) - ref_color.astype(np.int16))
        assert difference.max() <= 2, f"{scene}: {int(difference.max())}/255 at {np.argwhere(difference > 2)[:3]}"


@pytest.mark.sim
def test_shadows_are_drawn_as_sapiens_default_pack_drew_them(repo_root: Path, tmp_path: Path) -> None:
    """No shipped scene casts shadows, but a scene file may ask for them (`shadow: true`): the tabletop with a
    shadow-casting directional and point light. Shadow edges are sampled from slightly different positions
    (the default pack rebuilds them from the depth buffer), so a few edge pixels may differ; nothing else."""
    text = (repo_root / "scenes" / "tabletop.yaml").read_text().replace("calibration: tabletop.calibration.yaml\n", "")
    text += (
        "lights:\n"
        "  - {kind: ambient, color: [0.3, 0.3, 0.3]}\n"
        "  - {kind: directional, direction: [-0.3, 0.2, -1.0], color: [0.8, 0.8, 0.8], shadow: true}\n"
        "  - {kind: point, position_m: [0.4, 0.5, 1.0], color: [1.5, 1.5, 1.5], shadow: true}\n"
        "  - {kind: point, position_m: [0.4, -0.5, 1.0], color: [0.5, 0.5, 0.5]}\n"
    )
    (tmp_path / "shadows.yaml").write_text(text)
    (tmp_path / "no_shadows.yaml").write_text(text.replace(", shadow: true", ""))
    world = World.from_file(tmp_path / "shadows.yaml", seed=3)
    color, depth = world.camera.render_true()
    unshadowed = World.from_file(tmp_path / "no_shadows.yaml", seed=3).camera.render_true()[0]
    ref_color, ref_depth = _reference_pictures(world)

    np.testing.assert_array_equal(depth, ref_depth)
    difference = np.abs(color.astype(np.int16) - ref_color.astype(np.int16)).max(axis=-1)
    assert (difference > 2).mean() < 1e-4
    darker = unshadowed.astype(np.int16).sum(-1) - color.astype(np.int16).sum(-1)
    assert (darker > 30).mean() > 0.05  # the shadows are there (a shadowless pack would fail the comparison)
