"""Place, PlaceOn and MoveTo tick by tick with a stand-in robot (real kinematics and planner; the arm
follows its joint targets exactly unless a test makes it stop, as contact would)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.geometry import make_T
from bt_grasp.motion.executor import ExecutorOptions
from bt_grasp.motion.kinematics import default_kinematics
from bt_grasp.motion.planner import PlannerOptions, default_planner
from bt_grasp.motion.trajectory import MotionLimits
from bt_grasp.perception.results import Detection, GraspCandidate
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.tree.loader import load_tree_from_string

KIN = default_kinematics()
R_DOWN = np.diag([1.0, -1.0, -1.0])
HELD = Detection("red", (0, 0, 1, 1), (0.5, 0.0, 0.025), (0.05, 0.05, 0.05), 0.0, 100, 1.0)
BLUE = Detection("blue", (0, 0, 1, 1), (0.4, -0.2, 0.0225), (0.05, 0.05, 0.045), 0.3, 100, 1.0)
# grasped 1 cm above the held box's centre
GRASP = GraspCandidate(make_T(R_DOWN, [0.5, 0.0, 0.035]), make_T(R_DOWN, [0.5, 0.0, 0.135]), 0.05, 1.0, "test")


class ContactRobot(FakeRobot):
    """Follows joint targets, except that the tcp cannot go below ``floor_z`` (contact); the fingers hold an
    object 5 cm wide."""

    def __init__(self, floor_z: float = -1.0, fingers_open: bool = True) -> None:
        super().__init__(object_width_m=0.05)
        self.floor_z = floor_z
        self.fingers_open = fingers_open
        self.width, self.target = 0.05, 0.0
        lifted = make_T(R_DOWN, [0.5, 0.0, 0.185])
        self.q = KIN.ik(lifted, np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])).q

    def set_joint_targets(self, q_rad: Any, qd_rad_s: Any = None) -> None:
        if KIN.fk(np.asarray(q_rad))[2, 3] >= self.floor_z:
            self.q = np.asarray(q_rad, dtype=float)

    def open_gripper(self) -> None:
        if self.fingers_open:
            self.target = MAX_OPENING_M


def run(body: str, robot: ContactRobot, values: dict[str, Any], during: Any = None, ticks: int = 3000
        ) -> tuple[list[str], Any]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    clock = ManualClock()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = fake_cell(robot, clock)
    cell.kinematics, cell.planner, cell.planner_options = KIN, default_planner(), PlannerOptions(seed=1)
    cell.motion_limits, cell.executor_options = MotionLimits(), ExecutorOptions(settle_timeout_s=0.3)
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in values.items():
        tree.root_blackboard.set(key, value)
    statuses: list[str] = []
    for tick in range(ticks):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        if during is not None:
            during(tick, robot)
        robot.step()
        clock.advance_s(0.01)
    return statuses, tree


HOLDING = {"grasp": GRASP, "target": HELD, "objects": (HELD, BLUE)}


def tcp_z(robot: FakeRobot) -> float:
    return float(KIN.fk(robot.q)[2, 3])


def test_place_carries_descends_opens_and_retreats() -> None:
    # RUNNING while carrying, descending, opening and retreating; then SUCCESS with the fingers open.
    robot = ContactRobot()
    lowest: list[float] = []
    statuses, tree = run('<Place pose="0.35;0.2;0.0;90"/>', robot, HOLDING, lambda t, r: lowest.append(tcp_z(r)))
    assert statuses[-1] == "SUCCESS", tree.find("Place").feedback_message
    assert set(statuses[:-1]) == {"RUNNING"} and len(statuses) > 50
    # lowest tool height: surface 0 + half the box 0.025 + release gap 0.003 + grasp 1 cm above the centre
    assert min(lowest) == pytest.approx(0.038, abs=1e-3)
    T = KIN.fk(robot.q)
    assert np.allclose(T[:2, 3], (0.35, 0.2), atol=1e-3)
    assert T[2, 3] == pytest.approx(0.038 + 0.08, abs=2e-3)  # retreated 8 cm
    assert abs(abs(np.degrees(np.arctan2(T[1, 0], T[0, 0]))) - 90) < 0.5  # yawed to 90 (or -90: symmetric)
    assert robot.target == MAX_OPENING_M


def test_place_touching_down_early_within_the_window_counts_as_set_down() -> None:
    robot = ContactRobot(floor_z=0.045)  # contact 7 mm above the planned release height
    statuses, tree = run('<Place pose="0.35;0.2"/>', robot, HOLDING)
    assert statuses[-1] == "SUCCESS", tree.find("Place").feedback_message
    assert robot.target == MAX_OPENING_M


def test_place_met_early_fails_place_blocked() -> None:
    robot = ContactRobot(floor_z=0.09)  # something 5 cm above the target
    statuses, tree = run('<Place pose="0.35;0.2"/>', robot, HOLDING)
    assert statuses[-1] == "FAILURE"
    assert tree.blackboard_values()["failure_reason"] == "PLACE_BLOCKED"
    assert robot.target == 0.0  # never let go


def test_place_onto_an_occupied_target_fails_place_blocked() -> None:
    statuses, tree = run('<Place pose="0.4;-0.2"/>', ContactRobot(), HOLDING)
    assert statuses[-1] == "FAILURE" and tree.blackboard_values()["failure_reason"] == "PLACE_BLOCKED"


def test_place_with_nothing_held_fails_not_holding_at_once() -> None:
    robot = ContactRobot()
    robot.target = MAX_OPENING_M
    statuses, tree = run('<Place pose="0.35;0.2"/>', robot, HOLDING)
    assert statuses == ["FAILURE"] and tree.blackboard_values()["failure_reason"] == "NOT_HOLDING"


def test_place_losing_the_object_while_carrying_fails_dropped() -> None:
    def slip(tick: int, robot: FakeRobot) -> None:
        if tick == 20:
            robot.object_width_m = 0.0
            robot.width = 0.0

    statuses, tree = run('<Place pose="0.35;0.2"/>', ContactRobot(), HOLDING, slip)
    assert statuses[-1] == "FAILURE" and len(statuses) == 22
    assert tree.blackboard_values()["failure_reason"] == "DROPPED"


def test_place_out_of_reach_fails_ik_unreachable() -> None:
    statuses, tree = run('<Place pose="{far}"/>', ContactRobot(), {**HOLDING, "far": "1.6;0.0"})
    assert statuses == ["FAILURE"] or statuses[-1] == "FAILURE"
    assert tree.blackboard_values()["failure_reason"] == "IK_UNREACHABLE"


def test_place_without_a_grasp_fails_bad_input() -> None:
    statuses, tree = run('<Place pose="0.35;0.2"/>', ContactRobot(), {"target": HELD, "objects": ()})
    assert statuses == ["FAILURE"] and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


def test_place_fingers_that_do_not_open_fail_timeout() -> None:
    statuses, tree = run('<Place pose="0.35;0.2"/>', ContactRobot(fingers_open=False), HOLDING)
    assert statuses[-1] == "FAILURE" and tree.blackboard_values()["failure_reason"] == "TIMEOUT"


def test_place_on_puts_the_object_centred_on_top_of_the_other() -> None:
    robot = ContactRobot()
    lowest: list[Any] = []
    statuses, tree = run('<PlaceOn object="{base}"/>', robot, {**HOLDING, "base": BLUE},
                         lambda t, r: lowest.append(KIN.fk(r.q)))
    assert statuses[-1] == "SUCCESS", tree.find("PlaceOn").feedback_message
    T = min(lowest, key=lambda T: T[2, 3])
    # blue top 0.045 + half the held box + gap + 1 cm grasp offset, centred on blue, turned to blue's yaw
    assert T[2, 3] == pytest.approx(0.045 + 0.025 + 0.003 + 0.01, abs=1e-3)
    assert np.allclose(T[:2, 3], (0.4, -0.2), atol=1e-3)


def test_place_on_without_an_object_fails_bad_input() -> None:
    statuses, tree = run('<PlaceOn object="{base}"/>', ContactRobot(), {**HOLDING, "base": None})
    assert statuses == ["FAILURE"] and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


def test_move_to_reaches_the_pose_and_defaults_to_15_cm_above_the_table() -> None:
    robot = ContactRobot()
    statuses, _ = run('<MoveTo pose="0.4;0.1"/>', robot, {})
    assert statuses[-1] == "SUCCESS"
    assert np.allclose(KIN.fk(robot.q)[:3, 3], (0.4, 0.1, 0.15), atol=1e-3)
    statuses, _ = run('<MoveTo pose="0.45;-0.1;0.2;0;world"/>', robot, {})
    assert statuses[-1] == "SUCCESS" and np.allclose(KIN.fk(robot.q)[:3, 3], (0.45, -0.1, 0.2), atol=1e-3)


def test_move_to_out_of_reach_fails_ik_unreachable() -> None:
    statuses, tree = run('<MoveTo pose="2.0;0.0"/>', ContactRobot(), {})
    assert statuses[-1] == "FAILURE" and tree.blackboard_values()["failure_reason"] == "IK_UNREACHABLE"


class GripLog(ContactRobot):
    """A ContactRobot that keeps every gripper command (force, or 'open') with the tool height at the time."""

    def __init__(self, floor_z: float = -1.0) -> None:
        super().__init__(floor_z)
        self.commands: list[tuple[str, float | None, float]] = []

    def close_gripper(self, force_n: float | None = None) -> None:
        self.commands.append(("close", force_n, tcp_z(self)))
        super().close_gripper(force_n)

    def open_gripper(self) -> None:
        self.commands.append(("open", None, tcp_z(self)))
        super().open_gripper()


#: a can standing 12 cm tall on a 5 cm footprint, grasped 1 cm above its centre
CAN = Detection("red", (0, 0, 1, 1), (0.5, 0.0, 0.06), (0.05, 0.05, 0.12), 0.0, 100, 1.0)
CAN_GRASP = GraspCandidate(make_T(R_DOWN, [0.5, 0.0, 0.07]), make_T(R_DOWN, [0.5, 0.0, 0.17]), 0.05, 1.0, "test")


def test_a_standing_object_is_let_down_onto_the_surface_and_the_grip_eased_before_the_fingers_open() -> None:
    # carry, descend to the release pose (3 mm above), go on down by the gap and 2 mm more (contact would stop
    # it: here nothing does), ease the grip from 40 N to 4 N one step a tick over 0.3 s, open, retreat: SUCCESS
    from bt_grasp.behaviours.place import EASE_FORCE_N, EASE_S, TOUCH_DOWN_PRESS_M

    robot = GripLog()
    lowest: list[float] = []
    statuses, tree = run('<Place pose="0.35;0.2"/>', robot, {"grasp": CAN_GRASP, "target": CAN, "objects": ()},
                         lambda t, r: lowest.append(tcp_z(r)))
    assert statuses[-1] == "SUCCESS", tree.find("Place").feedback_message
    release_z = 0.06 + 0.003 + 0.01  # surface 0 + half the can + release gap + grasp offset
    assert min(lowest) == pytest.approx(release_z - 0.003 - TOUCH_DOWN_PRESS_M, abs=1e-3)
    forces = [f for kind, f, _ in robot.commands if kind == "close"]
    assert len(forces) == pytest.approx(EASE_S / 0.01, abs=1.5)  # one a tick
    assert forces == sorted(forces, reverse=True) and forces[0] <= 40.0 and forces[-1] >= EASE_FORCE_N
    assert forces[-1] < 6.0
    kinds = [kind for kind, _, _ in robot.commands]
    assert kinds[-1] == "open" and kinds.count("open") == 1
    # the grip was eased and the fingers opened with the can down on the surface, not above it
    assert all(z == pytest.approx(min(lowest), abs=1e-3) for _, _, z in robot.commands)


def test_a_standing_object_stopped_by_the_surface_is_still_let_go() -> None:
    # the surface is 1 mm under the release pose: the touch-down stalls there (a tracking error), and that is
    # where the can is let go
    robot = GripLog(floor_z=0.06 + 0.003 + 0.01 - 0.001)
    statuses, tree = run('<Place pose="0.35;0.2"/>', robot, {"grasp": CAN_GRASP, "target": CAN, "objects": ()})
    assert statuses[-1] == "SUCCESS", tree.find("Place").feedback_message
    assert [kind for kind, _, _ in robot.commands][-1] == "open"


def test_a_lying_object_is_let_go_at_the_release_pose_after_the_grip_is_eased() -> None:
    # a box as tall as it is wide does not tip: no touch-down (the lowest tool height is the release pose's), but
    # its grip is eased too, one step a tick, before the fingers open there
    from bt_grasp.behaviours.place import EASE_S

    robot = GripLog()
    lowest: list[float] = []
    statuses, _ = run('<Place pose="0.35;0.2"/>', robot, HOLDING, lambda t, r: lowest.append(tcp_z(r)))
    assert statuses[-1] == "SUCCESS"
    assert min(lowest) == pytest.approx(0.038, abs=1e-3)
    kinds = [kind for kind, _, _ in robot.commands]
    assert kinds[-1] == "open" and kinds.count("open") == 1
    assert kinds.count("close") == pytest.approx(EASE_S / 0.01, abs=1.5)
    assert all(z == pytest.approx(0.038, abs=1e-3) for _, _, z in robot.commands)
