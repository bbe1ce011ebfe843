"""The dataset's domain randomisation (`bt-grasp detector dataset`): table surfaces, the mount rule, the wrist
camera aimed at the workspace, a scene draw that cannot place its objects drawn again, and the segmentation pack.

Expected, worked out before the code:
- every texture kind but ``plain`` gives an RGBA image around the table colour whose texels vary (a pattern), the
  same seed the same texels, another seed other texels; ``plain`` gives None (the scene's own flat table);
- ``--mount both`` alternates each scene's pictures between the two mounts, whatever the number of scenes
  (four scenes: pictures 0-3 eye-to-hand, 4-7 eye-in-hand; one scene: alternating picture by picture);
- an eye-in-hand picture's camera looks at the workspace (its optical axis meets the table inside it, grown by
  5 cm) from at least 30 cm above the table, and the manifest records the arm joints used;
- the ``trivial`` pack's segmentation equals the ``default`` pack's, pixel for pixel, on the same world.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.interfaces import Mount
from bt_grasp.scene.colors import rgb_of
from bt_grasp.scene.format import load_scene
from bt_grasp.sim.labelling import (
    SCENE_LOOK_JITTER,
    WRIST_MIN_HEIGHT_M,
    WRIST_VIEW_MARGIN_M,
    SegmentationCamera,
    _mount_for,
    build_world,
    randomised_scene,
    view_centre_xy,
)
from bt_grasp.sim.table_texture import TEXTURE_KINDS, texture_image

ROOT = Path(__file__).resolve().parents[2]
HOUSEHOLD = ROOT / "scenes" / "household.yaml"


@pytest.mark.parametrize("kind", [k for k in TEXTURE_KINDS if k != "plain"])
def test_each_texture_is_a_seeded_pattern_around_the_table_colour(kind: str) -> None:
    base = (0.55, 0.45, 0.35)
    a = texture_image(kind, base, np.random.default_rng(3), size=128)
    b = texture_image(kind, base, np.random.default_rng(3), size=128)
    c = texture_image(kind, base, np.random.default_rng(4), size=128)
    assert a is not None and b is not None and c is not None
    assert a.shape == (128, 128, 4) and a.dtype == np.uint8 and (a[..., 3] == 255).all()
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    rgb = a[..., :3].astype(float) / 255.0
    assert rgb.std(axis=(0, 1)).max() > 0.01  # a pattern, not a flat colour
    if kind != "tiles":  # tiles' grout has a colour of its own
        assert np.abs(np.median(rgb, axis=(0, 1)) - base).max() < 0.15


def test_plain_is_the_scenes_own_table_and_an_unknown_kind_is_refused() -> None:
    assert texture_image("plain", (0.5, 0.5, 0.5), np.random.default_rng(0)) is None
    with pytest.raises(ValueError, match="unknown table texture 'marble'"):
        texture_image("marble", (0.5, 0.5, 0.5), np.random.default_rng(0))


def test_a_third_of_the_pictures_have_the_scenes_own_look() -> None:
    """The pipeline's camera sees the scene's wood-coloured plain table under the scene's lights: about a third of
    the draws (SCENE_LOOK_SHARE) keep them (table colour within 0.04 per channel), the rest draw a grey, a surface
    and lights."""
    config = load_scene(HOUSEHOLD)
    own = rgb_of(config.table.color)
    draws = [randomised_scene(config, np.random.default_rng([7, i]), Mount.EYE_TO_HAND) for i in range(300)]
    looks = [what for _, what in draws if what.scene_look]
    assert 75 <= len(looks) <= 125  # 100 expected of 300 (binomial sd ~8)
    for drawn, what in draws:
        if what.scene_look:
            assert what.table_texture == "plain" and drawn.lights == config.lights
            assert np.allclose(what.table_rgb, own, atol=SCENE_LOOK_JITTER + 1e-9)
            assert np.allclose(rgb_of(drawn.table.color), what.table_rgb)
        else:
            assert drawn.lights != config.lights
    # the drawn greys never come this close to the wood colour in all three channels at once
    others = [what.table_rgb for _, what in draws if not what.scene_look]
    assert not any(np.allclose(rgb, own, atol=0.02) for rgb in others)


def test_both_mounts_alternate_within_each_scene() -> None:
    config = load_scene(HOUSEHOLD)
    four = [_mount_for("both", config, i, 4) for i in range(8)]
    assert four == [Mount.EYE_TO_HAND] * 4 + [Mount.EYE_IN_HAND] * 4
    one = [_mount_for("both", config, i, 1) for i in range(4)]
    assert one == [Mount.EYE_TO_HAND, Mount.EYE_IN_HAND] * 2
    assert _mount_for("scene", config, 5, 4) == Mount(config.camera.mount)


@pytest.mark.sim
@pytest.mark.parametrize("index", range(3))
def test_the_wrist_camera_looks_at_the_workspace(index: int, monkeypatch: pytest.MonkeyPatch,
                                                 tmp_path: Path) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path))
    config = load_scene(HOUSEHOLD)
    rng = np.random.default_rng([11, index])
    drawn, what = randomised_scene(config, rng, Mount.EYE_IN_HAND)
    world, used = build_world(HOUSEHOLD, drawn, what, rng)
    home = np.asarray(config.robot.home_q_rad)
    assert not np.allclose(used.arm_q_rad, home)  # the arm was moved ...
    assert np.allclose(world.robot.joint_positions(), used.arm_q_rad, atol=1e-5)  # ... to the joints recorded
    seen = view_centre_xy(world)
    assert seen is not None
    x, y, height = seen
    ws = config.workspace
    assert ws.x_m[0] - WRIST_VIEW_MARGIN_M <= x <= ws.x_m[1] + WRIST_VIEW_MARGIN_M
    assert ws.y_m[0] - WRIST_VIEW_MARGIN_M <= y <= ws.y_m[1] + WRIST_VIEW_MARGIN_M
    assert height >= WRIST_MIN_HEIGHT_M


@pytest.mark.sim
def test_a_draw_that_cannot_place_its_objects_is_drawn_again(monkeypatch: pytest.MonkeyPatch,
                                                             tmp_path: Path) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path))
    import bt_grasp.sim.labelling as labelling
    from bt_grasp.errors import ConfigError

    config = load_scene(HOUSEHOLD)
    rng = np.random.default_rng(5)
    drawn, what = randomised_scene(config, rng, Mount.EYE_TO_HAND)
    real_world = labelling.World
    calls: list[int] = []

    def first_fails(scene: object, seed: int, **kwargs: object) -> object:
        calls.append(seed)
        if len(calls) == 1:
            raise ConfigError(HOUSEHOLD, "cannot place object 'plate' without overlapping others", "objects")
        return real_world(scene, seed, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(labelling, "World", first_fails)
    _, used = build_world(HOUSEHOLD, drawn, what, rng)
    assert len(calls) == 2 and calls[0] == what.world_seed and used.world_seed == calls[1] != calls[0]


@pytest.mark.sim
def test_the_trivial_pack_segments_as_the_default_pack(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path))
    import sapien

    import bt_grasp.sim.labelling as labelling

    config = load_scene(HOUSEHOLD)
    rng = np.random.default_rng(2)
    drawn, what = randomised_scene(config, rng, Mount.EYE_TO_HAND)
    world, _ = build_world(HOUSEHOLD, drawn, what, rng)
    trivial = SegmentationCamera(world).masks()
    default = os.path.join(os.path.dirname(sapien.__file__), "vulkan_shader", "default")
    monkeypatch.setattr(labelling, "_segmentation_shader_dir", lambda: default)
    by_default = SegmentationCamera(world).masks()
    assert set(trivial) == set(by_default) and sum(int(m.sum()) for m in trivial.values()) > 500
    for name, mask in trivial.items():
        assert np.array_equal(mask, by_default[name]), name
