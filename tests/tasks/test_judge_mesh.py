"""The judge on mesh objects (issue 28): bottom, top, centre and rise from each object's true geometry.

The household meshes have their origin at their bottom, not their centre; an object may also lie in a rest
pose other than the modelled one. A stand-in oracle holds the poses here (no simulator runs): each judged
condition (at_target, on_top, in_container, lifted, the work area) is checked for a mesh whose origin is its
bottom, a bottle lying on its side, and primitives as before. The simulator's own case is
tests/motion/test_sim_6dof_grasps.py (a side-grasped bottle placed on the marker, judged at_target).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.geometry import Mat4

REPO = Path(__file__).resolve().parents[2]
BOTTLE = REPO / "bt_grasp" / "assets" / "household" / "bottle.obj"
MARKER_XY = (0.36, 0.24)
BIN_XY = (0.30, -0.40)

pytestmark = pytest.mark.sim  # importing the judge imports the simulator's oracle (no world is built here)

#: a 4 x 6 x 10 cm block whose origin is the centre of its bottom face (z from 0 to 0.10)
BLOCK_OBJ = "\n".join(
    [f"v {x} {y} {z}" for z in (0.0, 0.10) for y in (-0.03, 0.03) for x in (-0.02, 0.02)]
    + ["f 1 3 4", "f 1 4 2", "f 5 6 8", "f 5 8 7", "f 1 2 6", "f 1 6 5",
       "f 3 7 8", "f 3 8 4", "f 1 5 7", "f 1 7 3", "f 2 4 8", "f 2 8 6"]) + "\n"

SCENE = """version: 2
name: judge_mesh
calibration: {calibration}
physics: {{timestep_s: 0.002, control_rate_hz: 100}}
table: {{size_m: [1.0, 1.4, 0.04], center_xy_m: [0.35, 0.0], color: wood}}
robot: {{base_xyz_m: [0.0, 0.0, 0.0], home_q_rad: [0.0, -1.9, 1.9, -1.57, -1.57, 0.0], gripper_force_n: 40}}
camera:
  mount: eye-to-hand
  eye_to_hand: {{position_m: [1.05, 0.0, 0.75], look_at_m: [0.45, 0.0, 0.0]}}
fixtures:
  - {{kind: marker, name: target_marker, center_xy_m: {marker}, size_m: [0.08, 0.08], color: yellow}}
  - {{kind: bin, name: bin, center_xy_m: {bin}, inner_size_m: [0.36, 0.24], color: grey}}
objects:
  - {{name: block, shape: mesh, mesh: {block}, mass_kg: 0.2, color: red, pose: {{xy_m: [0.5, 0.0]}}}}
  - {{name: bottle, shape: mesh, mesh: {bottle}, mass_kg: 0.4, color: green, pose: {{xy_m: [0.5, 0.1]}}}}
  - {{name: cube, shape: box, size_m: [0.04, 0.04, 0.04], color: blue, pose: {{xy_m: [0.5, -0.1]}}}}
  - {{name: tin, shape: cylinder, size_m: [0.03, 0.08], color: yellow, pose: {{xy_m: [0.5, -0.2]}}}}
"""


def _T(xyz: tuple[float, float, float], R: np.ndarray | None = None) -> Mat4:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = xyz
    return T


def _rx(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class StandInOracle:
    """Poses set by the test; held objects touch both fingers; nothing moves between observations."""

    def __init__(self, poses: dict[str, Mat4]) -> None:
        self.poses = dict(poses)
        self.held: set[str] = set()

    def object_names(self) -> tuple[str, ...]:
        return tuple(self.poses)

    def T_world_object(self, name: str) -> Mat4:
        return self.poses[name]

    def object_in_gripper(self, name: str) -> bool:
        return name in self.held

    def object_touches_fingers(self, name: str) -> bool:
        return name in self.held

    def object_velocity(self, name: str) -> np.ndarray:
        return np.zeros(3)


class StandInWorld:
    """What the judge reads of a world besides the oracle: the scene, the clock, the tick length."""

    def __init__(self, config: object) -> None:
        self.config = config
        self.t_ns = 0
        self.dt_s = 0.002
        self.steps_per_tick = 5
        self.entered: dict[str, object] = {}  # no conveyor feed

    def now_ns(self) -> int:
        return self.t_ns


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> object:
    from bt_grasp.scene.format import load_scene

    folder = tmp_path_factory.mktemp("judge_mesh")
    (folder / "block.obj").write_text(BLOCK_OBJ)
    path = folder / "judge_mesh.yaml"
    path.write_text(SCENE.format(calibration=REPO / "scenes" / "tabletop.calibration.yaml", block=folder / "block.obj",
                                 bottle=BOTTLE, marker=list(MARKER_XY), bin=list(BIN_XY)))
    return load_scene(path)


#: where every object starts: standing on the table as modelled (mesh origins at the bottom, primitives' centres)
START = {"block": _T((0.5, 0.0, 0.0)), "bottle": _T((0.5, 0.1, 0.0)), "cube": _T((0.5, -0.1, 0.02)),
         "tin": _T((0.5, -0.2, 0.04))}


def _placed(scene: object, moves: dict[str, Mat4], goal: dict[str, object]):  # type: ignore[no-untyped-def]
    """Each object of ``moves`` picked up, put at its pose, let go, and left still 1.5 s; the verdict on ``goal``."""
    from pydantic import TypeAdapter

    from bt_grasp.scene.goals import Goal
    from bt_grasp.sim.judge import Judge

    oracle, world = StandInOracle(START), StandInWorld(scene)
    judge = Judge(world, oracle)  # type: ignore[arg-type]
    oracle.held = set(moves)
    world.t_ns += 10_000_000
    judge.observe()
    oracle.poses.update(moves)
    world.t_ns += 10_000_000
    judge.observe()  # carried there, still held
    oracle.held = set()
    world.t_ns += 10_000_000
    judge.observe()  # released where it stands
    world.t_ns += 1_500_000_000
    judge.observe()
    return judge.check(TypeAdapter(Goal).validate_python(goal))


def _met(verdict) -> dict[str, bool]:  # type: ignore[no-untyped-def]
    return {c.criterion.value: c.met for c in verdict.conditions}


def _detail(verdict, criterion: str) -> str:  # type: ignore[no-untyped-def]
    return next(c.detail for c in verdict.conditions if c.criterion.value == criterion)


PLACE = {"kind": "place", "object": "block", "at": "target_marker"}


def test_a_mesh_whose_origin_is_its_bottom_standing_on_the_marker_is_at_target(scene: object) -> None:
    verdict = _placed(scene, {"block": _T((*MARKER_XY, 0.0))}, PLACE)
    assert verdict.success, verdict.conditions
    assert "bottom 0 mm above" in _detail(verdict, "at_target")


def test_a_mesh_held_2_cm_above_the_marker_or_beside_it_is_not_at_target(scene: object) -> None:
    above = _placed(scene, {"block": _T((*MARKER_XY, 0.02))}, PLACE)
    assert not _met(above)["at_target"] and "bottom 20 mm above" in _detail(above, "at_target")
    beside = _placed(scene, {"block": _T((MARKER_XY[0] + 0.02, MARKER_XY[1], 0.0))}, PLACE)
    assert not _met(beside)["at_target"] and "2.0 cm from the target" in _detail(beside, "at_target")


def test_a_lying_bottle_is_judged_by_its_lowest_point_and_its_centre(scene: object) -> None:
    """Lying along x (turned 90 deg about y), the bottle's bottom is its radius under its axis, not half its
    height; its centre is half its length along the axis from its origin (the bottom face's centre)."""
    spec = scene.object_spec("bottle")  # type: ignore[attr-defined]
    (lo, hi) = spec.geometry.bounds_m
    radius, length = (hi[1] - lo[1]) / 2, hi[2] - lo[2]
    assert length > 0.15 and 0.02 < radius < 0.04
    # the origin (the bottom face's centre) half a length before the marker's centre, the axis one radius up
    origin = (MARKER_XY[0] - length / 2, MARKER_XY[1] - (hi[1] + lo[1]) / 2, radius)
    verdict = _placed(scene, {"bottle": _T(origin, _ry(90.0))}, {"kind": "place", "object": "bottle",
                                                                 "at": "target_marker"})
    met = _met(verdict)
    assert met["at_target"], _detail(verdict, "at_target")
    assert not met["upright"]  # lying is not upright: that condition stays the placement tracker's
    floating = _placed(scene, {"bottle": _T((origin[0], origin[1], radius + 0.01), _ry(90.0))},
                       {"kind": "place", "object": "bottle", "at": "target_marker"})
    assert not _met(floating)["at_target"] and "bottom 10 mm above" in _detail(floating, "at_target")


def test_a_primitive_box_is_judged_as_before(scene: object) -> None:
    goal = {"kind": "place", "object": "cube", "at": "target_marker"}
    assert _placed(scene, {"cube": _T((*MARKER_XY, 0.02))}, goal).success
    assert not _met(_placed(scene, {"cube": _T((*MARKER_XY, 0.04))}, goal))["at_target"]


def test_stacked_on_and_under_a_mesh_whose_origin_is_its_bottom(scene: object) -> None:
    """The block's bottom on the cube's top (origin at z = 0.04), and the cube's bottom on the block's top
    (centre at 0.10 + 0.02); each 8 mm too high is not stacked."""
    on_cube = {"kind": "stack", "object": "block", "on": "cube"}
    assert _placed(scene, {"block": _T((0.5, -0.1, 0.04))}, on_cube).success
    high = _placed(scene, {"block": _T((0.5, -0.1, 0.048))}, on_cube)
    assert not _met(high)["on_top"] and "its bottom 8 mm above cube's top" in _detail(high, "on_top")
    on_block = {"kind": "stack", "object": "cube", "on": "block"}
    assert _placed(scene, {"cube": _T((0.5, 0.0, 0.12))}, on_block).success
    assert not _met(_placed(scene, {"cube": _T((0.5, 0.0, 0.128))}, on_block))["on_top"]


def test_in_the_bin_by_the_mesh_bottom_and_the_lying_bottles_centre(scene: object) -> None:
    floor = 0.004  # the bin's floor thickness (Container's default)
    goal = {"kind": "clear", "into": "bin"}
    standing = {"block": _T((BIN_XY[0] - 0.08, BIN_XY[1], floor)), "cube": _T((BIN_XY[0], BIN_XY[1], floor + 0.02)),
                "tin": _T((BIN_XY[0] + 0.08, BIN_XY[1], floor + 0.04)), "bottle": _T((BIN_XY[0], BIN_XY[1] + 0.07,
                                                                                    floor))}
    assert _placed(scene, standing, goal).success
    raised = _placed(scene, {**standing, "block": _T((BIN_XY[0] - 0.08, BIN_XY[1], floor + 0.02))}, goal)
    assert not _met(raised)["in_container"] and "block not on the floor" in _detail(raised, "in_container")
    # the bottle lying with its origin inside the bin's -x wall and its centre well inside is in the bin
    spec = scene.object_spec("bottle")  # type: ignore[attr-defined]
    lo, hi = spec.geometry.bounds_m
    radius, length = (hi[1] - lo[1]) / 2, hi[2] - lo[2]
    lying = _T((BIN_XY[0] - 0.17, BIN_XY[1] + 0.07, floor + radius), _ry(90.0))
    assert (BIN_XY[0] - 0.17) + length / 2 < BIN_XY[0] + 0.18  # its centre inside the 36 cm floor
    verdict = _placed(scene, {**standing, "bottle": lying}, goal)
    assert _met(verdict)["in_container"], _detail(verdict, "in_container")


def test_the_rise_of_a_lying_mesh_picked_up_standing_is_its_centres(scene: object) -> None:
    """The block lies on its side (its origin 3 cm up, its centre 5 cm beside it), is lifted and turns upright
    in the fingers: its centre rose 15 cm, its origin only 10."""
    from bt_grasp.scene.goals import PickGoal
    from bt_grasp.sim.judge import Judge

    lying = _T((0.5, 0.0, 0.03), _rx(90.0))  # local y -> world z: lowest point at z = 0.03 - 0.03
    oracle, world = StandInOracle({**START, "block": lying}), StandInWorld(scene)
    judge = Judge(world, oracle)  # type: ignore[arg-type]
    assert judge.extent("block").bottom_z_m == pytest.approx(0.0)
    assert judge.extent("block").center_m == pytest.approx((0.5, -0.05, 0.03))
    oracle.poses["block"] = _T((0.5, -0.05, 0.03 + 0.15 - 0.05))  # upright, centre at 0.18
    oracle.held = {"block"}
    verdict = judge.check(PickGoal(kind="pick", object="block", height_m=0.15))
    assert verdict.success and verdict.object_lift_m == pytest.approx(0.15), verdict.conditions
    oracle.poses["block"] = _T((0.5, -0.05, 0.03 + 0.10 - 0.05))  # centre only 10 cm up
    assert not _met(judge.check(PickGoal(kind="pick", object="block", height_m=0.15)))["lifted"]


def test_a_lying_cylinder_and_a_tilted_box_reach_down_by_their_rims_and_corners(scene: object) -> None:
    from bt_grasp.sim.judge_view import object_extent

    tin, cube = scene.object_spec("tin"), scene.object_spec("cube")  # type: ignore[attr-defined]
    lying = object_extent(tin, _T((0.5, 0.0, 0.03), _ry(90.0)))  # radius 3 cm under the axis, height 8 cm
    assert (lying.bottom_z_m, lying.top_z_m) == pytest.approx((0.0, 0.06))
    tilted = object_extent(tin, _T((0.5, 0.0, 0.1), _ry(30.0)))
    assert tilted.bottom_z_m == pytest.approx(0.1 - 0.04 * math.cos(math.radians(30)) - 0.03 * 0.5)
    corner = object_extent(cube, _T((0.5, 0.0, 0.1), _rx(45.0)))  # on an edge: half the face diagonal
    assert corner.bottom_z_m == pytest.approx(0.1 - 0.02 * math.sqrt(2))
