"""Every robot leaf, tick by tick, with stand-ins (no simulator): success and each failure reason.

PlanGrasp/Approach are in test_plan_approach_leaves.py, Grasp in test_gripper_leaves.py. The robot stand-in
follows joint targets at once and moves its fingers 5 mm per tick; the camera returns synthetic RGB-D frames
(the perception tests' ray caster); kinematics and Cartesian segments are the real ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from behaviour_fakes import FakePlanner, FakeRobot, fake_cell
from perception_synth import DEFAULT_T_BASE_CAMERA, INTRINSICS, Box, render

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import Cell
from bt_grasp.clock import ManualClock
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.motion.planner import PlanStatus
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string

REPO = Path(__file__).resolve().parents[2]
HOME = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


class SynthCamera:
    """Returns the synthetic frame it was given (None: a dropped frame)."""

    mount = Mount.EYE_TO_HAND
    intrinsics: CameraIntrinsics = INTRINSICS

    def __init__(self, frame: RGBDFrame | None) -> None:
        self.frame = frame

    def capture(self) -> RGBDFrame | None:
        return self.frame


class FixedCalibration:
    mount = "eye-to-hand"
    tool_link = "tool0"

    def T_base_camera_at(self, T_base_tool: np.ndarray | None = None) -> np.ndarray:
        return DEFAULT_T_BASE_CAMERA


def _tree(xml_body: str, cell: Cell, clock: ManualClock) -> LoadedTree:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{xml_body}</BehaviorTree></root>'
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    return tree


def _run(tree: LoadedTree, robot: FakeRobot, clock: ManualClock, max_ticks: int = 2000) -> list[str]:
    statuses = []
    for _ in range(max_ticks):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return statuses


def _cell(frame: RGBDFrame | None = None, calibrated: bool = True) -> tuple[Cell, FakeRobot, ManualClock]:
    clock, robot = ManualClock(), FakeRobot()
    robot.q = HOME.copy()
    cell = fake_cell(robot, clock)
    cell.camera = SynthCamera(frame)
    cell.calibration = FixedCalibration() if calibrated else None
    return cell, robot, clock


def _reason(tree: LoadedTree) -> str:
    return str(tree.blackboard_values()["failure_reason"])


# --- Perceive and ObjectVisible: one capture, one tick ------------------------------------------------------

PERCEIVE = '<Perceive color="{color}" target="{target}" objects="{objects}"/>'


def test_perceive_finds_the_red_box_in_one_tick() -> None:
    cell, robot, clock = _cell(render([Box((0.45, 0.0), (0.05, 0.05, 0.05))]))
    tree = _tree(PERCEIVE, cell, clock)
    tree.root_blackboard.set("color", "red")
    assert _run(tree, robot, clock) == ["SUCCESS"]
    target = tree.root_blackboard.get("target")
    assert target.label == "red" and abs(target.centroid_base_m[0] - 0.45) < 0.01


@pytest.mark.parametrize(
    ("frame", "calibrated", "color", "reason"),
    [
        (render([Box((0.45, 0.0), (0.05, 0.05, 0.05))]), False, "red", "CALIBRATION_MISSING"),
        (None, True, "red", "NO_FRAME"),
        (render([Box((0.45, 0.0), (0.05, 0.05, 0.05))]), True, "mauve", "BAD_INPUT"),
        (render([]), True, "red", "NO_DETECTION"),  # an empty table
    ],
)
def test_perceive_failures(frame: RGBDFrame | None, calibrated: bool, color: str, reason: str) -> None:
    cell, robot, clock = _cell(frame, calibrated)
    tree = _tree(PERCEIVE, cell, clock)
    tree.root_blackboard.set("color", color)
    assert _run(tree, robot, clock) == ["FAILURE"]
    assert _reason(tree) == reason


def test_object_visible_is_a_one_tick_condition() -> None:
    cell, robot, clock = _cell(render([Box((0.45, 0.0), (0.05, 0.05, 0.05))]))
    assert _run(_tree('<ObjectVisible color="red"/>', cell, clock), robot, clock) == ["SUCCESS"]
    cell, robot, clock = _cell(render([]))
    tree = _tree('<ObjectVisible color="red"/>', cell, clock)
    assert _run(tree, robot, clock) == ["FAILURE"] and _reason(tree) == "NO_DETECTION"


# --- moving leaves: RUNNING while the trajectory plays, then SUCCESS --------------------------------------


def _tool_z(cell: Cell, robot: FakeRobot) -> float:
    return float(cell.kinematics.fk(robot.q)[2, 3])


@pytest.mark.parametrize(("xml", "rise_m"), [('<Lift height="0.1"/>', 0.1), ('<Retreat height="0.05"/>', 0.05)])
def test_straight_up_leaves_rise_by_their_height(xml: str, rise_m: float) -> None:
    cell, robot, clock = _cell()
    robot.width = 0.05  # holding a 5 cm object (Lift checks the fingers)
    robot.object_width_m = 0.05
    robot.target = 0.0
    z0 = _tool_z(cell, robot)
    statuses = _run(_tree(xml, cell, clock), robot, clock)
    assert statuses[-1] == "SUCCESS" and set(statuses[:-1]) == {"RUNNING"} and len(statuses) > 2
    assert abs(_tool_z(cell, robot) - z0 - rise_m) < 1e-3


def test_lift_fails_slipped_when_the_fingers_close_on_nothing() -> None:
    cell, robot, clock = _cell()
    robot.width, robot.target, robot.object_width_m = 0.003, 0.0, 0.0  # closed on nothing
    tree = _tree('<Lift height="0.1"/>', cell, clock)
    assert _run(tree, robot, clock) == ["FAILURE"]
    assert _reason(tree) == "SLIPPED"


def test_lift_refuses_a_height_out_of_range() -> None:
    cell, robot, clock = _cell()
    tree = _tree('<Lift height="0.9"/>', cell, clock)
    assert _run(tree, robot, clock) == ["FAILURE"]
    assert _reason(tree) == "BAD_INPUT"


def test_move_home_and_move_above_plan_then_move() -> None:
    for xml in ("<MoveHome/>", '<MoveAbove x="0.45" y="0.1" height="0.2"/>'):
        cell, robot, clock = _cell()
        cell.planner = FakePlanner()
        statuses = _run(_tree(xml, cell, clock), robot, clock)
        assert statuses[-1] == "SUCCESS" and set(statuses[:-1]) == {"RUNNING"}, xml
        assert len(cell.planner.pose_calls) == (1 if "MoveAbove" in xml else 0)


@pytest.mark.parametrize(
    ("status", "reason"),
    [(PlanStatus.NO_PATH, "PLAN_FAILED"), (PlanStatus.IK_UNREACHABLE, "IK_UNREACHABLE"),
     (PlanStatus.GOAL_IN_COLLISION, "COLLISION"), (PlanStatus.START_IN_COLLISION, "COLLISION")],
)
def test_planned_moves_fail_with_the_planners_reason(status: PlanStatus, reason: str) -> None:
    cell, robot, clock = _cell()
    cell.planner = FakePlanner((status,))
    tree = _tree('<MoveAbove x="0.45" y="0.1" height="0.2"/>', cell, clock)
    assert _run(tree, robot, clock) == ["FAILURE"]
    assert _reason(tree) == reason


# --- gripper: OpenGripper, IsGrasped -------------------------------------------------------------------------


def test_open_gripper_opens_then_succeeds() -> None:
    cell, robot, clock = _cell()
    robot.width = robot.target = 0.0
    statuses = _run(_tree("<OpenGripper/>", cell, clock), robot, clock)
    # 85 mm at 5 mm per tick: 17 steps; SUCCESS once within 2 mm of fully open (after 17 ticks of RUNNING)
    assert statuses == ["RUNNING"] * 17 + ["SUCCESS"]
    assert robot.width == pytest.approx(MAX_OPENING_M)


def test_open_gripper_times_out_when_the_fingers_are_blocked() -> None:
    cell, robot, clock = _cell()
    robot.width, robot.target = 0.0, 0.0
    robot.step = lambda: None  # type: ignore[method-assign]  # the fingers do not move
    tree = _tree("<OpenGripper/>", cell, clock)
    statuses = _run(tree, robot, clock)
    # timeout 1.5 s at 10 ms per tick: RUNNING until more than 1.5 s passed (151 ticks), then FAILURE
    assert statuses == ["RUNNING"] * 151 + ["FAILURE"]
    assert _reason(tree) == "TIMEOUT"


@pytest.mark.parametrize(
    ("width", "target", "status", "reason"),
    [(0.05, 0.0, "SUCCESS", None), (0.085, 0.085, "FAILURE", "GRASP_EMPTY"), (0.002, 0.0, "FAILURE", "SLIPPED")],
)
def test_is_grasped(width: float, target: float, status: str, reason: str | None) -> None:
    cell, robot, clock = _cell()
    robot.width, robot.target = width, target
    tree = _tree("<IsGrasped/>", cell, clock)
    assert _run(tree, robot, clock) == [status]
    if reason is not None:
        assert _reason(tree) == reason


# --- calibration leaves -----------------------------------------------------------------------------------


def test_load_calibration_loads_the_file_and_fails_without_one(tmp_path: Path) -> None:
    cell, robot, clock = _cell(calibrated=False)
    tree = _tree('<LoadCalibration file="{calibration_file}"/>', cell, clock)
    tree.root_blackboard.set("calibration_file", str(REPO / "tests/data/calibration/tabletop_eye_to_hand.yaml"))
    assert _run(tree, robot, clock) == ["SUCCESS"]
    assert cell.calibration is not None and cell.calibration.mount == "eye-to-hand"
    for file in ("", str(tmp_path / "missing.yaml")):
        cell, robot, clock = _cell(calibrated=False)
        tree = _tree('<LoadCalibration file="{calibration_file}"/>', cell, clock)
        tree.root_blackboard.set("calibration_file", file)
        assert _run(tree, robot, clock) == ["FAILURE"] and _reason(tree) == "CALIBRATION_MISSING"


def test_calibrate_without_a_board_fails_at_once() -> None:
    cell, robot, clock = _cell(calibrated=False)
    tree = _tree('<Calibrate poses="15"/>', cell, clock)
    assert _run(tree, robot, clock) == ["FAILURE"]
    assert _reason(tree) == "CALIBRATION_FAILED"
    assert tree.find("Calibrate").feedback_message == "no calibration board is mounted in this cell"
