"""Seeded object subsets (``choose``) and rest poses (``rest_pose``) in scene files, and scenes/household.yaml:
same seed, same scene; different seeds, different subsets; every drawn scene places its objects apart; some
objects stand and some lie across seeds; bad keys are one sentence with file:line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.cli.main import main
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.scene.layout import TILT_BIN_DEG, draw_layout, stable_rest_poses
from bt_grasp.sim.objects import PlacedObject, draw_poses, footprint_gap_m, footprint_xy

from .conftest import MESHES

REPO = Path(__file__).resolve().parents[2]
HOUSEHOLD = REPO / "scenes" / "household.yaml"
SEEDS = range(40)


@pytest.fixture(scope="module")
def household() -> Scene:
    return load_scene(HOUSEHOLD)


def drawn(scene: Scene, seed: int) -> list[PlacedObject]:
    """What World draws for a seed, without building a simulator: the same stream, the same calls."""
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[0])
    layout = draw_layout(scene, rng)
    return draw_poses(layout.objects, rng, 0.0, "scene", scene.object_gap_m, layout.rest)


def tilt_deg(p: PlacedObject) -> float:
    return float(np.degrees(np.arccos(np.clip(p.T_world_object[2, 2], -1.0, 1.0))))


def test_same_seed_same_objects_and_poses(household: Scene) -> None:
    for seed in (0, 1, 7):
        a, b = drawn(household, seed), drawn(household, seed)
        assert [p.spec.name for p in a] == [p.spec.name for p in b]
        for pa, pb in zip(a, b, strict=True):
            np.testing.assert_array_equal(pa.T_world_object, pb.T_world_object)
    again = drawn(load_scene(HOUSEHOLD), 7)  # a fresh load (stable poses computed again) draws the same
    np.testing.assert_array_equal(np.stack([p.T_world_object for p in again]),
                                  np.stack([p.T_world_object for p in drawn(household, 7)]))


def test_different_seeds_draw_different_subsets_of_three_to_five(household: Scene) -> None:
    subsets = [tuple(p.spec.name for p in drawn(household, seed)) for seed in SEEDS]
    assert all(3 <= len(s) <= 5 for s in subsets), subsets
    assert len(set(subsets)) >= 30, "40 seeds should give (almost) 40 different subsets of 12 objects"
    assert {len(s) for s in subsets} == {3, 4, 5}
    assert {n for s in subsets for n in s} == {o.name for o in household.objects}, "every object shows up"


def test_every_drawn_scene_keeps_its_objects_apart_in_the_workspace(household: Scene) -> None:
    assert household.object_gap_m == 0.01
    for seed in SEEDS:
        placed = drawn(household, seed)
        for i, a in enumerate(placed):
            x, y = a.T_world_object[:2, 3]
            assert household.workspace.x_m[0] <= x <= household.workspace.x_m[1]
            assert household.workspace.y_m[0] <= y <= household.workspace.y_m[1]
            lowest = (a.spec.geometry.vertices_m @ a.T_world_object[:3, :3].T)[:, 2].min() + a.T_world_object[2, 3]
            assert lowest == pytest.approx(0.002, abs=1e-9), "dropped from 2 mm above the table"
            for b in placed[i + 1:]:
                gap = footprint_gap_m(footprint_xy(a.spec, a.T_world_object), footprint_xy(b.spec, b.T_world_object))
                assert gap >= 0.01 - 1e-9, (seed, a.spec.name, b.spec.name, gap)


def test_some_objects_stand_and_some_lie_across_seeds(household: Scene) -> None:
    tilts: dict[str, set[int]] = {}
    for seed in range(100):  # each object is in a third of the scenes; each of its rest poses in a third of those
        for p in drawn(household, seed):
            tilts.setdefault(p.spec.name, set()).add(round(tilt_deg(p) / TILT_BIN_DEG) * int(TILT_BIN_DEG))
    for name in ("mug", "bottle", "can"):  # modelled standing, drawn any_stable: seen standing and lying
        assert {0, 90} <= tilts[name], (name, tilts[name])
    for name in ("banana", "pen", "plate"):  # rest_pose modelled: always as the file lies
        assert tilts.get(name, {0}) == {0}, (name, tilts[name])


def test_rest_poses_are_the_mesh_s_own_and_stable(household: Scene) -> None:
    bottle = household.object_spec("bottle")
    assert bottle is not None
    poses = stable_rest_poses(bottle.geometry)
    assert sum(p.probability for p in poses) <= 1.0 + 1e-9
    assert {round(p.tilt_deg / TILT_BIN_DEG) * 10 for p in poses} == {0, 90}, "standing or lying, never on its cap"
    for p in poses:
        np.testing.assert_allclose(p.R @ p.R.T, np.eye(3), atol=1e-9)
        assert np.linalg.det(p.R) == pytest.approx(1.0)


def test_a_scene_without_the_new_keys_draws_nothing_more(tmp_path: Path) -> None:
    scene = load_scene(REPO / "scenes" / "household_clear.yaml")
    assert scene.choose is None and all(o.rest_pose == "modelled" for o in scene.objects)
    rng = np.random.default_rng(3)
    layout = draw_layout(scene, rng)
    assert layout.objects == scene.objects and layout.rest == {}
    assert rng.uniform() == np.random.default_rng(3).uniform(), "the stream is untouched: old poses per seed"


def test_choose_among_names_keeps_the_others(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(f"""version: 2
choose: {{among: [a, b, c], count: 1}}
objects:
  - {{name: a, shape: box, size_m: [0.04, 0.04, 0.04], color: red, pose: {{xy_m: [0.4, 0.0]}}}}
  - {{name: b, shape: box, size_m: [0.04, 0.04, 0.04], color: blue, pose: {{xy_m: [0.5, 0.0]}}}}
  - {{name: c, shape: box, size_m: [0.04, 0.04, 0.04], color: green, pose: {{xy_m: [0.6, 0.0]}}}}
  - {{name: keep, shape: mesh, mesh: {MESHES / 'box.obj'}, rest_pose: stable, pose: {{xy_m: [0.5, 0.2]}}}}
""")
    scene = load_scene(path)
    kept = {tuple(o.name for o in draw_layout(scene, np.random.default_rng(s)).objects) for s in range(20)}
    assert kept == {("a", "keep"), ("b", "keep"), ("c", "keep")}


def _scene(tmp_path: Path, body: str, version: int = 2) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(f"version: {version}\n" + body)
    return path


BOX = "{name: %s, shape: box, size_m: [0.04, 0.04, 0.04], color: red, pose: {xy_m: [0.5, 0.0]}}"
BAD = {
    "unknown name": ("choose: {among: [a, nope], count: 1}\nobjects:\n  - " + BOX % "a" + "\n",
                     2, "choose names object 'nope', which is not in the scene (objects: a)"),
    "twice": ("choose:\n  among: [a, a]\n  count: 1\nobjects:\n  - " + BOX % "a" + "\n",
              3, "choose names object 'a' twice"),
    "too many": ("choose:\n  count: [1, 3]\nobjects:\n  - " + BOX % "a" + "\n  - " + BOX % "b" + "\n",
                 3, "choose draws up to 3 objects among 2"),
    "reversed count": ("choose:\n  count: [3, 1]\nobjects:\n  - " + BOX % "a" + "\n",
                       3, "count is a number or [low, high] with low <= high"),
    "unknown key": ("choose:\n  count: 1\n  from: [a]\nobjects:\n  - " + BOX % "a" + "\n",
                    4, "unknown key 'from' (expected one of: among, count)"),
    "goal may lose its object": ("choose: {count: 1}\nobjects:\n  - " + BOX % "a" + "\n  - " + BOX % "b"
                                 + "\ngoal: {kind: pick, object: b}\n",
                                 6, "the goal names object 'b', which choose may leave out of a run"),
    "rest pose on a box": ("objects:\n  - {name: a, shape: box, size_m: [0.04, 0.04, 0.04], color: red,\n"
                           "     rest_pose: stable, pose: {xy_m: [0.5, 0.0]}}\n",
                           3, "'rest_pose' is for mesh or urdf objects, not a box"),
    "unknown rest pose": (f"objects:\n  - name: m\n    shape: mesh\n    mesh: {MESHES / 'box.obj'}\n"
                          "    rest_pose: lying\n    pose: {xy_m: [0.5, 0.0]}\n",
                          6, "rest_pose: Input should be 'modelled', 'stable' or 'any_stable'"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_choose_or_rest_pose_is_one_sentence_with_file_line(case: str, tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    body, line, fragment = BAD[case]
    path = _scene(tmp_path, body)
    assert main(["scene", "validate", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"bt-grasp: error: {path}:{line}: "), err[0]
    assert fragment in err[0], err[0]


def test_choose_needs_version_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "v1.yaml"
    path.write_text("choose: {count: 1}\nobjects:\n  - " + BOX % "a" + "\n")
    assert main(["scene", "validate", str(path)]) == 2
    assert "'choose' needs scene format version 2" in capsys.readouterr().err


def test_the_wedge_training_scene_puts_the_wood_wedge_on_every_table(household: Scene) -> None:
    """scenes/training/household_wedge.yaml (the detector's run-4 dataset): the household objects as they are in
    scenes/household.yaml, 3 to 5 per table like it, and the wood wedge always among them (it is left out of
    ``choose.among``), on the scene's own wood-coloured table."""
    wedge_scene = load_scene(REPO / "scenes" / "training" / "household_wedge.yaml")
    assert [(o.name, o.mass_kg, o.friction, o.color, o.rest_pose) for o in wedge_scene.objects] == \
        [(o.name, o.mass_kg, o.friction, o.color, o.rest_pose) for o in household.objects]
    assert wedge_scene.table == household.table
    counts = set()
    for seed in SEEDS:
        names = [p.spec.name for p in drawn(wedge_scene, seed)]
        assert "wedge" in names, seed
        counts.add(len(names))
    assert counts == {3, 4, 5}
