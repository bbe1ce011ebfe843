"""LookAt's view geometry (no simulator), and the eye-in-hand pick in the simulator: the XML tree and its
YAML twin succeed by physics and tick identically on the same seed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.behaviours.viewing import parse_point, tool_pose_for_view
from bt_grasp.geometry import T_from_xyz_rpy

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes/eye_in_hand.yaml"
T_TOOL_CAMERA = T_from_xyz_rpy(np.array([-0.07, 0.0, 0.01]), np.deg2rad([0.0, 12.0, 0.0]))


@pytest.mark.parametrize("point", [(0.5, 0.0, 0.0), (0.4, -0.25, 0.02), (0.45, 0.2, 0.05)])
@pytest.mark.parametrize("distance", [0.4, 0.62])
def test_the_view_puts_the_point_on_the_optical_axis_at_the_distance(point: tuple[float, ...], distance: float
                                                                      ) -> None:
    p = np.array(point)
    T_tool = tool_pose_for_view(p, distance, T_TOOL_CAMERA)
    assert T_tool[:3, 2] @ np.array([0.0, 0.0, -1.0]) == pytest.approx(1.0)  # the tool points down
    assert T_tool[:3, 0] @ np.array([p[0], p[1], 0.0]) > 0  # tool x points away from the base
    T_cam = T_tool @ T_TOOL_CAMERA
    in_cam = np.linalg.inv(T_cam) @ np.array([*p, 1.0])
    assert in_cam[:2] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert in_cam[2] == pytest.approx(distance)


def test_view_points_parse_like_btcpp_vectors() -> None:
    assert parse_point("0.5;0.1;0") == pytest.approx([0.5, 0.1, 0.0])
    assert parse_point("0.5, 0.1, 0") == pytest.approx([0.5, 0.1, 0.0])
    assert parse_point("workspace") is None and parse_point("1;2") is None and parse_point("a;b;c") is None


@pytest.mark.sim
@pytest.mark.slow
def test_eye_in_hand_pick_xml_and_yaml_twins_succeed_and_tick_identically(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.reader import open_log

    streams = []
    for tree in ("trees/pick_eye_in_hand.xml", "trees/pick_eye_in_hand.yaml"):
        log = tmp_path / f"{Path(tree).suffix[1:]}.mcap"
        request = EpisodeRequest(tree=REPO / tree, scene=SCENE, seed=3, log=log,
                                 blackboard={"color": "red", "lift_height": 0.15})
        result = run_episode(request)
        assert result.success, result
        run = open_log(log)
        paths = {uid: info.path for uid, info in run.structures[0].nodes().items()}
        streams.append([{paths[n.uid]: n.status for n in tick.nodes if n.ticked} for tick in run.ticks])
    assert streams[0] == streams[1]
    # the survey, the first look, the close view and the refining perception each succeeded, in that order
    # (coarse to fine)
    first_success: dict[str, int] = {}
    for i, tick in enumerate(streams[0]):
        for path, status in tick.items():
            for name in ("survey", "find", "close_view", "refine"):
                if path.rsplit("/", 1)[-1].split("@")[0] == name and str(status).endswith("SUCCESS"):
                    first_success.setdefault(name, i)
    assert sorted(first_success, key=first_success.__getitem__) == ["survey", "find", "close_view", "refine"], (
        first_success
    )


_VIEW_TREE = """<root BTCPP_format="4" main_tree_to_execute="T">
  <BehaviorTree ID="T">
    <Sequence>
      <LoadCalibration file="{calibration_file}"/>
      <LookAt view="%s"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.mark.parametrize(("view", "fragment"), [("1.6;0;0.2", "out of the arm's reach"),
                                                ("over there", "nor a point 'x;y;z'"),
                                                ("workspace-up", "neither 'workspace', 'workspace-near'")])
def test_a_bad_literal_view_exits_2_with_file_and_line(tmp_path: Path, view: str, fragment: str) -> None:
    import subprocess
    import sys

    tree = tmp_path / "far.xml"
    tree.write_text(_VIEW_TREE % view)
    log = tmp_path / "run.mcap"
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "run", str(tree), "--scene", str(SCENE),
                           "--log", str(log)], capture_output=True, text=True, timeout=300, cwd=REPO)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{tree}:5" in lines[0] and fragment in lines[0], proc.stderr
    assert not log.exists()


@pytest.mark.sim
def test_an_unreachable_view_from_the_blackboard_fails_with_ik_unreachable(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode

    tree = tmp_path / "far.xml"
    tree.write_text(_VIEW_TREE % "{far}")
    request = EpisodeRequest(tree=tree, scene=SCENE, seed=0, blackboard={"color": "red", "far": "1.6;0;0.2"})
    result = run_episode(request)
    assert not result.success and result.reason == "IK_UNREACHABLE" and result.failed_leaf == "LookAt"
    assert result.ticks <= 3  # refused before moving


def test_a_second_look_takes_one_half_of_the_work_area_from_closer() -> None:
    from bt_grasp.behaviours.viewing import HALF_VIEW_DISTANCE_M, workspace_view
    from bt_grasp.scene.format import load_scene

    scene = load_scene(SCENE)  # the default work area: x 0.25-0.75, y -0.35-0.35 (world = base here)
    expected = {"workspace-near": (0.375, 0.0), "workspace-far": (0.625, 0.0), "workspace-left": (0.5, 0.175),
                "workspace-right": (0.5, -0.175)}
    for view, xy in expected.items():
        looked = workspace_view(scene, view)
        assert not isinstance(looked, str)
        assert looked[0][:2] == pytest.approx(xy) and looked[1] == HALF_VIEW_DISTANCE_M
    assert isinstance(workspace_view(scene, "workspace-middle"), str)


def _leaf_starts(substitutions: dict[str, str]) -> tuple[str, list[str], object]:
    """Tick trees/pick_eye_in_hand.xml with every robot leaf a stand-in (RUNNING a tick, then SUCCESS) unless
    ``substitutions`` says otherwise, by name; the names of the LookAt and Perceive leaves in the order they
    started, and the final status and reason."""
    import sys

    sys.path.insert(0, str(REPO / "tests" / "behaviours"))
    from behaviour_fakes import FakeRobot, fake_cell

    from bt_grasp.behaviours import robot_registry
    from bt_grasp.clock import ManualClock
    from bt_grasp.tree.loader import load_tree

    stand_ins = {spec.name: "Running:1" for spec in robot_registry(installed=False).specs() if spec.needs_robot}
    clock = ManualClock()
    tree = load_tree(REPO / "trees" / "pick_eye_in_hand.xml", robot_registry(),
                     substitutions={**substitutions, **stand_ins}, clock=clock)
    cell = fake_cell(FakeRobot(), clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    started: list[str] = []
    before: dict[str, str] = {}
    for _ in range(200):
        status = tree.tick()
        for node in tree.nodes():
            state = node.bt_state.value
            if node.name in ("survey", "look_left", "look_right", "close_view", "find", "find_left", "find_right",
                             "refine") and state != before.get(node.bt_path, "IDLE") and state in ("RUNNING",):
                started.append(node.name)
            before[node.bt_path] = state
        if status.completed:
            return status.value, started, tree.blackboard_values().get("failure_reason")
        clock.advance_s(0.01)
    raise AssertionError("the tree did not finish")


def test_not_seen_from_the_survey_the_tree_looks_again_over_each_half_before_giving_up() -> None:
    # tick by tick (each stand-in RUNNING one tick): survey, find -> NO_DETECTION; look_left, find_left ->
    # NO_DETECTION; look_right, find_right -> SUCCESS; then the close view and the refining look
    status, started, _ = _leaf_starts({"find": "Running:1:Failure:NO_DETECTION",
                                       "find_left": "Running:1:Failure:NO_DETECTION"})
    assert status == "SUCCESS"
    assert started == ["survey", "find", "look_left", "find_left", "look_right", "find_right", "close_view", "refine"]
    # seen at once: no second look
    status, started, _ = _leaf_starts({})
    assert status == "SUCCESS" and started == ["survey", "find", "close_view", "refine"]
    # seen from no view: NO_DETECTION after the three looks, nothing moved towards an object
    status, started, reason = _leaf_starts({n: "Running:1:Failure:NO_DETECTION" for n in ("find", "find_left",
                                                                                          "find_right")})
    assert status == "FAILURE" and reason == "NO_DETECTION"
    assert started == ["survey", "find", "look_left", "find_left", "look_right", "find_right"]


@pytest.mark.sim
def test_a_box_at_the_work_areas_edge_is_found_by_the_second_look(tmp_path: Path) -> None:
    # the red box at (0.40, -0.31): the survey's view does not reach it (find: NO_DETECTION; on main before the
    # second look the run ended there); the right half's closer look finds it, and it is picked
    from bt_grasp.episode import EpisodeRequest, run_episode

    text = SCENE.read_text().replace("pose: {xy_m: [0.50, 0.0], yaw_deg: 0}", "pose: {xy_m: [0.40, -0.31], yaw_deg: 0}")
    text = text.replace("randomize: {x_m: [-0.06, 0.06], y_m: [-0.06, 0.06], yaw_deg: [-90, 90]}",
                        "randomize: {x_m: [-0.01, 0.01], y_m: [-0.01, 0.01]}")
    text = text.replace("calibration: eye_in_hand.calibration.yaml",
                        f"calibration: {REPO / 'scenes' / 'eye_in_hand.calibration.yaml'}")
    scene = tmp_path / "edge.yaml"
    scene.write_text(text)
    assert "[0.40, -0.31]" in text
    request = EpisodeRequest(tree=REPO / "trees" / "pick_eye_in_hand.xml", scene=scene, seed=0,
                             blackboard={"color": "red", "lift_height": 0.15})
    result = run_episode(request)
    assert result.success, result
    first = result.failure_chain[0]
    assert first.leaf_path.rsplit("/", 1)[-1].startswith("find") and first.reason == "NO_DETECTION", first
