"""Every shipped tree end to end on the simulator, judged by physics (issue 26).

Each ``trees/*.xml`` runs on its shipped scene with one fixed seed (known to succeed) through the episode API,
in one process with a warm renderer (``WarmWorlds``, module-scoped, as ``bt-grasp bench tasks`` runs them).
Each case asserts the judge's verdict (the episode summary, simulator ground truth) AND a property of its own
task, computed in this file from the judge's final object poses, the oracle or the written files, so a wrong
checker in the judge would not pass unnoticed:

==========================  ==============================  ====================================================
tree                        scene                           task property checked here
==========================  ==============================  ====================================================
pick.xml                    tabletop.yaml                   only the red box rose (15 cm), held by both fingers;
                                                            the other objects did not move
pick_with_recovery.xml      tabletop.yaml                   as pick, and a clean run needs no recovery (no retry)
pick_and_place.xml          pick_and_place.yaml             the red box rests on the marker, within 1 cm of its
                                                            centre, its bottom on the table
stack.xml                   stack.yaml                      the red box rests centred on the blue box's top; the
                                                            blue box was not pushed
sort_by_color.xml           sort_by_color.yaml              every red object on the left tray's floor, every blue
                                                            one on the right tray's
clear_table.xml             clear_table.yaml                no object left in the work area: each on the bin's floor
calibrate.xml               tabletop.yaml                   the calibration file written by the run is within
                                                            2 mm / 0.2 deg of the true camera pose; nothing tipped
follow_conveyor.xml         conveyor_follow.yaml            median tracking error <= 5 mm after convergence (the
                                                            ``bench follow`` measurement, reused), the box travelled
                                                            on the belt at its speed
==========================  ==============================  ====================================================

Runs that already exist elsewhere (not repeated here with the same checks):

* ``pick_eye_in_hand.xml``: ``tests/eye_in_hand/test_look_at.py::
  test_eye_in_hand_pick_xml_and_yaml_twins_succeed_and_tick_identically`` (seed 3, success by physics, the four
  views in order, the YAML twin ticks identically).
* ``pick_class.xml``: ``tests/behaviours/test_pick_class_sim.py::test_pick_class_xml_picks_the_mug_by_class``
  (household seed 0, the mug picked by class, success by physics; its detector a stand-in that sees the true
  masks, the shipped model's figures being ``bench pick --detector learned``'s).
* ``pick_from_conveyor.xml``: ``tests/conveyor/test_conveyor.py::
  test_pick_from_the_conveyor_succeeds_by_physics_and_logs_the_servo`` (seed 2, both mounts, success by
  physics, the servo's phases logged).
* ``pick.xml`` also runs in ``tests/test_run_cli.py::test_pick_succeeds_replays_and_resimulates`` (through the
  CLI, success and lift, replay, re-simulation), ``tests/tasks/test_scene_schema.py::
  test_the_newcomer_command_succeeds_with_no_other_flag`` and ``tests/episode/test_warm_world.py``;
  ``pick_with_recovery.xml`` in ``tests/episode/test_warm_world.py`` (fingerprints), ``tests/episode/
  test_fingerprint_in_process.py`` and ``tests/faults/test_sim_faults.py`` (every recovery, with faults). The
  cases here check what those do not: which object rose and that nothing else moved, and no retry on a clean run.

``test_every_shipped_tree_is_run_on_the_simulator`` (no simulator) keeps this true: a new ``trees/*.xml`` with
no case here and no named test elsewhere fails it.

The bounds: a noise-free hand-eye calibration recovers the camera to ~0.03 mm / 0.002 deg
(``bt-grasp calibrate``); 2 mm / 0.2 deg cannot flake but catches a wrong frame convention (a swapped axis or
an inverted transform is off by decimetres or degrees). ``docs/following.md`` measured a median tracking
error of 1.35 mm at 5 cm/s with the fixed camera (its goal: <= 5 mm); a follower without the belt's velocity
fed forward lags by ~12 mm (v / kp).
"""

from __future__ import annotations

import ast
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from bt_grasp.defaults import DEFAULT_MAX_TICKS

if TYPE_CHECKING:
    from bt_grasp.episode import Episode, EpisodeResult, WarmWorlds

REPO = Path(__file__).resolve().parents[2]
#: where calibrate.xml writes its file (the tree's {calibration_out}), inside the test's tmp_path
CALIBRATION_OUT = "calibration.yaml"

#: millimetre-scale slack for "did not move" (the objects settle by a fraction of a millimetre)
STILL_M = 0.002
#: calibration against the true camera pose
CALIBRATION_MAX_MM = 2.0
CALIBRATION_MAX_DEG = 0.2
#: following: the followed box, the ticks of the run (FollowTarget starts at tick 1; ``bench follow`` judges
#: from 3 s after that: 200 judged ticks) and the bound on the median error
FOLLOWED = "red_box"
FOLLOW_TICKS = 500
FOLLOW_MEDIAN_MAX_MM = 5.0


@dataclass
class Run:
    """One finished episode: the prepared episode (its world still there), the result, where things began."""

    episode: Episode
    result: EpisodeResult
    start_xyz_m: dict[str, np.ndarray]
    tmp: Path
    follow_errors_m: list[float]

    def end_xyz_m(self, name: str) -> np.ndarray:
        """An object's final centre, from the judge's final poses (simulator ground truth)."""
        return np.array(self.result.judged.object_poses[name])[:3, 3]

    def moved_m(self, name: str) -> np.ndarray:
        return self.end_xyz_m(name) - self.start_xyz_m[name]

    def height_m(self, name: str) -> float:
        spec = self.episode.scene.object_spec(name)
        assert spec is not None, name
        return float(spec.height_m)

    def objects(self) -> list[str]:
        return [o.name for o in self.episode.scene.objects]

    def fixture(self, name: str) -> Any:  # a fixture of any kind (tray, bin, marker, conveyor)
        return next(f for f in self.episode.scene.fixtures if f.name == name)


def _inside_container(run: Run, name: str, container_name: str) -> str | None:
    """Why ``name`` is not resting on the floor of ``container_name`` (None when it is), computed here from
    the container's centre, yaw and inner size (not with the judge's own geometry)."""
    box = run.fixture(container_name)
    xyz = run.end_xyz_m(name)
    yaw = np.deg2rad(box.yaw_deg)
    d = xyz[:2] - np.array(box.center_xy_m)
    local = np.array([np.cos(yaw) * d[0] + np.sin(yaw) * d[1], -np.sin(yaw) * d[0] + np.cos(yaw) * d[1]])
    half = np.array(box.inner_size_m) / 2
    if np.any(np.abs(local) > half):
        return f"{name} at {xyz[:2].round(3)} is outside {container_name}'s walls"
    bottom = xyz[2] - run.height_m(name) / 2
    floor = box.floor_thickness_m
    if abs(bottom - floor) > 0.005:
        return f"{name}'s bottom is {1e3 * (bottom - floor):+.1f} mm from {container_name}'s floor"
    return None


def _assert_judged_success(run: Run, criterion: str) -> None:
    result = run.result
    assert result.success and result.tree_status == "SUCCESS", result.to_json()
    assert result.judged.success and result.judged.failed_condition is None, result.judged.conditions
    met = {c: m for c, m, _ in result.judged.conditions}
    assert met.get(criterion) is True, f"the judge did not check {criterion}: {result.judged.conditions}"


def check_pick(run: Run) -> None:
    _assert_judged_success(run, "lifted")
    judged = run.result.judged
    assert judged.object_name == "red_box" and judged.in_gripper, judged
    assert run.moved_m("red_box")[2] >= 0.15 - 0.01, run.moved_m("red_box")
    assert judged.lifted_objects == ("red_box",), judged.lifted_objects
    for name in run.objects():
        if name != "red_box":
            assert np.linalg.norm(run.moved_m(name)) < STILL_M, f"{name} moved by {run.moved_m(name)} m"


def check_pick_with_recovery(run: Run) -> None:
    check_pick(run)
    assert run.result.retries == {}, f"a clean run needed a recovery: {run.result.retries}"


def check_pick_and_place(run: Run) -> None:
    _assert_judged_success(run, "at_target")
    marker = run.fixture("target_marker")
    xyz = run.end_xyz_m("red_box")
    off = float(np.hypot(*(xyz[:2] - np.array(marker.center_xy_m))))
    assert off <= 0.01, f"red_box rests {off * 100:.1f} cm from the marker's centre"
    assert abs(xyz[2] - run.height_m("red_box") / 2) <= 0.005, f"red_box's centre at z={xyz[2]:.3f} m"


def check_stack(run: Run) -> None:
    _assert_judged_success(run, "on_top")
    top, low = run.end_xyz_m("red_box"), run.end_xyz_m("blue_box")
    assert np.hypot(*(top[:2] - low[:2])) <= 0.03, (top, low)
    expected_z = low[2] + run.height_m("blue_box") / 2 + run.height_m("red_box") / 2
    assert abs(top[2] - expected_z) <= 0.005, f"red_box {1e3 * (top[2] - expected_z):+.1f} mm off blue_box's top"
    assert np.linalg.norm(run.moved_m("blue_box")) < 0.005, f"blue_box pushed by {run.moved_m('blue_box')} m"


def check_sort_by_color(run: Run) -> None:
    _assert_judged_success(run, "in_container")
    tray = {"red": "left_tray", "blue": "right_tray"}
    placed = [(o.name, tray[o.color]) for o in run.episode.scene.objects if o.color in tray]
    assert len(placed) == 4, placed
    problems = [p for name, box in placed if (p := _inside_container(run, name, box)) is not None]
    assert not problems, problems


def check_clear_table(run: Run) -> None:
    _assert_judged_success(run, "in_container")
    ws = run.episode.scene.workspace
    left = [n for n in run.objects()
            if ws.x_m[0] <= run.end_xyz_m(n)[0] <= ws.x_m[1] and ws.y_m[0] <= run.end_xyz_m(n)[1] <= ws.y_m[1]]
    assert not left, f"left in the work area: {left}"
    assert run.result.judged.objects_in_workspace == (), run.result.judged.objects_in_workspace
    problems = [p for n in run.objects() if (p := _inside_container(run, n, "bin")) is not None]
    assert not problems, problems


def check_calibrate(run: Run) -> None:
    from bt_grasp.geometry import pose_error
    from bt_grasp.perception.calibration_file import load_calibration
    from bt_grasp.sim.judge import true_camera_pose

    result = run.result
    # the scene declares no goal: the judge's pick verdict does not apply (the run is GOAL_NOT_MET by it, no leaf
    # blamed: issue 46's headline); the tree must succeed on its own
    assert result.tree_status == "SUCCESS" and result.reason == "GOAL_NOT_MET", result.to_json()
    assert result.failed_leaf is None, result.to_json()
    written = run.tmp / CALIBRATION_OUT
    assert written.is_file(), "the Calibrate leaf wrote no calibration file"
    calibration = load_calibration(written, mount="eye-to-hand")
    assert calibration.samples >= 15, calibration.samples
    T_true = true_camera_pose(run.episode.world, calibration.mount, calibration.tool_link)
    dt_m, dr_rad = pose_error(calibration.T_parent_camera, T_true)
    assert dt_m * 1e3 <= CALIBRATION_MAX_MM and np.degrees(dr_rad) <= CALIBRATION_MAX_DEG, (
        f"calibration {dt_m * 1e3:.3f} mm / {np.degrees(dr_rad):.4f} deg from the true camera pose")
    # by physics: the board's sweep lifted nothing and tipped nothing (every object still rests on the table).
    # Not asserted: that nothing was pushed. The views are planned against the installation only (the objects
    # are unknown before calibration): on this seed the sweep pushes blue_box ~10 mm sideways.
    assert result.judged.lifted_objects == (), result.judged.lifted_objects
    for name in run.objects():
        assert abs(run.moved_m(name)[2]) < STILL_M, f"{name} rose or fell by {run.moved_m(name)[2]} m"


def check_follow_conveyor(run: Run) -> None:
    result = run.result
    # the tree follows forever by design: it must still be running, never having lost the target
    assert result.tree_status == "RUNNING" and result.reason == "MAX_TICKS", result.to_json()
    errors_mm = np.array(run.follow_errors_m) * 1e3
    assert len(errors_mm) >= 150, f"only {len(errors_mm)} ticks judged after convergence"
    median = float(np.median(errors_mm))
    p95 = float(np.percentile(errors_mm, 95))
    assert median <= FOLLOW_MEDIAN_MAX_MM, f"median tracking error {median:.2f} mm (p95 {p95:.2f} mm)"
    # the target really travelled on the belt, at the belt's speed (a still target would track trivially)
    belt = next(f for f in run.episode.scene.fixtures if f.kind == "conveyor")
    assert belt.speed_m_s > 0.0, belt
    moved = run.moved_m(FOLLOWED)
    expected = belt.speed_m_s * result.sim_time_s
    assert moved[1] >= 0.8 * expected and abs(moved[0]) < 0.005, f"{FOLLOWED} moved {moved} m, belt {expected} m"


@dataclass(frozen=True)
class Case:
    scene: str
    seed: int
    check: Callable[[Run], None]
    max_ticks: int = DEFAULT_MAX_TICKS
    blackboard: tuple[tuple[str, str | float], ...] = (("color", "red"), ("lift_height", 0.15))


CASES: dict[str, Case] = {
    "pick.xml": Case("tabletop.yaml", 0, check_pick),
    "pick_with_recovery.xml": Case("tabletop.yaml", 0, check_pick_with_recovery),
    "pick_and_place.xml": Case("pick_and_place.yaml", 0, check_pick_and_place),
    "stack.xml": Case("stack.yaml", 0, check_stack),
    "sort_by_color.xml": Case("sort_by_color.yaml", 0, check_sort_by_color),
    "clear_table.xml": Case("clear_table.yaml", 0, check_clear_table),
    "calibrate.xml": Case("tabletop.yaml", 0, check_calibrate, blackboard=(("calibration_out", CALIBRATION_OUT),)),
    "follow_conveyor.xml": Case("conveyor_follow.yaml", 0, check_follow_conveyor, FOLLOW_TICKS, (("color", "red"),)),
}

#: shipped trees run end to end on the simulator by another test (path::name), with success by physics
ELSEWHERE: dict[str, str] = {
    "pick_eye_in_hand.xml": "tests/eye_in_hand/test_look_at.py::"
                            "test_eye_in_hand_pick_xml_and_yaml_twins_succeed_and_tick_identically",
    "pick_from_conveyor.xml": "tests/conveyor/test_conveyor.py::"
                              "test_pick_from_the_conveyor_succeeds_by_physics_and_logs_the_intercept",
    "sort_from_conveyor.xml": "tests/conveyor/test_conveyor.py::"
                              "test_sort_from_the_conveyor_puts_objects_in_the_bin_by_physics",
    "clear_household.xml": "tests/perception/test_clear_household_sim.py::"
                           "test_clear_household_puts_every_object_in_the_bin",
    "pick_class.xml": "tests/behaviours/test_pick_class_sim.py::test_pick_class_xml_picks_the_mug_by_class",
}


@pytest.fixture(scope="module")
def worlds() -> WarmWorlds:
    """One warm renderer for the module: its start-up (4-7 s on lavapipe) is paid once."""
    from bt_grasp.episode import WarmWorlds

    return WarmWorlds()


@pytest.mark.sim
@pytest.mark.parametrize("tree", list(CASES))
def test_shipped_tree_runs_end_to_end_on_its_scene(tree: str, worlds: WarmWorlds, tmp_path: Path) -> None:
    from bt_grasp.bench.follow import _follow_errors  # the measurement `bench follow` reports
    from bt_grasp.episode import Episode, EpisodeRequest
    from bt_grasp.sim.oracle import GroundTruthOracle

    case = CASES[tree]
    blackboard = {k: str(tmp_path / str(v)) if k == "calibration_out" else v for k, v in case.blackboard}
    request = EpisodeRequest(tree=REPO / "trees" / tree, scene=REPO / "scenes" / case.scene, seed=case.seed,
                             max_ticks=case.max_ticks, blackboard=blackboard)
    episode = Episode(request, worlds)
    oracle = GroundTruthOracle(episode.world)
    start = {n: oracle.T_world_object(n)[:3, 3].copy() for n in oracle.object_names()}
    errors: list[float] = []
    on_tick = []
    if tree == "follow_conveyor.xml":
        errors, follow = _follow_errors(episode, FOLLOWED)
        on_tick.append(follow)
    assert not (tmp_path / CALIBRATION_OUT).exists()
    result = episode.run(on_tick)
    case.check(Run(episode, result, start, tmp_path, errors))


def _test_function(path: Path, name: str) -> tuple[ast.FunctionDef, str, bool]:
    source = path.read_text()
    module = ast.parse(source)
    sim_module = any(isinstance(n, ast.Assign) and any(getattr(t, "id", "") == "pytestmark" for t in n.targets)
                     and "sim" in ast.unparse(n.value) for n in module.body)
    for node in module.body:
        if isinstance(node, ast.FunctionDef) and node.name == name:
            marked = sim_module or any("mark.sim" in ast.unparse(d) for d in node.decorator_list)
            return node, ast.get_source_segment(source, node) or "", marked
    raise AssertionError(f"{path.relative_to(REPO)} has no test {name}")


def test_every_shipped_tree_is_run_on_the_simulator() -> None:
    """Each trees/*.xml is a case above or is run, success judged by physics, by a named sim test elsewhere."""
    shipped = {p.name for p in (REPO / "trees").glob("*.xml")}
    assert not set(CASES) & set(ELSEWHERE)
    assert shipped == set(CASES) | set(ELSEWHERE), (
        f"not run on the simulator: {sorted(shipped - set(CASES) - set(ELSEWHERE))}; "
        f"not shipped: {sorted(set(CASES) | set(ELSEWHERE) - shipped)}")
    for tree, where in ELSEWHERE.items():
        path, name = where.split("::")
        _, source, marked = _test_function(REPO / path, name)
        assert marked, f"{where} is not a sim test"
        assert f"trees/{tree}" in source, f"{where} does not run trees/{tree}"
        assert "result.success" in source, f"{where} does not check success by physics"
