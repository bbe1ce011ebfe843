"""FollowTarget tick by tick with stand-ins: a robot that is where it is commanded, analytic RGB-D frames of
a red box on a table (no simulator), the real kinematic model.

* a box in view: RUNNING while the tool closes in, SUCCESS once the error stayed under the tolerance for
  ``converged_time``; the tool ends over the box at the standoff;
* the box leaves the view: RUNNING until ``lost_after`` s without a measurement, then FAILURE TARGET_LOST,
  and the arm is told to stop (joint velocity targets zero).
"""

from __future__ import annotations

import numpy as np
from behaviour_fakes import FakeRobot
from perception_synth import DEFAULT_T_BASE_CAMERA, Box, render

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import make_cell
from bt_grasp.clock import ManualClock
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.scene.format import Scene
from bt_grasp.tree.loader import load_tree_from_string

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <FollowTarget color="red" standoff="0.15" converged_time="0.3" lost_after="0.6" track="{track}"/>
  </BehaviorTree>
</root>
"""
BOX = Box((0.5, 0.05), (0.05, 0.05, 0.05), 0.2)


class _Calibration:
    mount = "eye-to-hand"
    tool_link = "tool0"

    def T_base_camera_at(self, T_base_tool: object = None) -> np.ndarray:
        return DEFAULT_T_BASE_CAMERA


class _Camera:
    mount = "eye-to-hand"

    def __init__(self) -> None:
        self.visible = True
        self._with, self._without = render([BOX], noise_m=0.001, seed=1), render([], noise_m=0.001, seed=2)

    def capture(self) -> RGBDFrame:
        return self._with if self.visible else self._without


class _Robot(FakeRobot):
    def __init__(self) -> None:
        super().__init__()
        self.q = np.asarray(Scene().robot.home_q_rad, dtype=float)
        self.qd = np.zeros(6)

    def set_joint_targets(self, q_rad: np.ndarray, qd_rad_s: np.ndarray | None = None) -> None:
        self.q = np.asarray(q_rad, dtype=float)
        self.qd = np.zeros(6) if qd_rad_s is None else np.asarray(qd_rad_s, dtype=float)


def _setup() -> tuple[object, _Robot, _Camera, ManualClock]:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, robot_registry(), clock=clock)
    robot, camera = _Robot(), _Camera()
    cell = make_cell(robot, camera, clock, Scene(), seed=0, calibration=_Calibration())  # type: ignore[arg-type]
    cell.kinematics = ArmKinematics()
    for node in tree.nodes():
        node.setup(cell=cell)
    return tree, robot, camera, clock


def test_follow_converges_over_a_box_in_view() -> None:
    tree, robot, _, clock = _setup()
    statuses = []
    for _ in range(600):
        statuses.append(tree.tick().value)  # type: ignore[attr-defined]
        if statuses[-1] != "RUNNING":
            break
        clock.advance_s(0.01)
    assert statuses[-1] == "SUCCESS" and set(statuses[:-1]) == {"RUNNING"}, statuses[-5:]
    assert len(statuses) > 30  # the converged time alone is 30 ticks
    tcp = ArmKinematics().fk(robot.q)[:3, 3]
    assert np.hypot(tcp[0] - 0.5, tcp[1] - 0.05) < 0.006
    assert abs(tcp[2] - (0.025 + 0.15)) < 0.006


def test_a_target_that_leaves_the_view_fails_with_target_lost_and_stops_the_arm() -> None:
    tree, robot, camera, clock = _setup()
    statuses = []
    for tick in range(300):
        if tick == 50:
            camera.visible = False
        statuses.append(tree.tick().value)  # type: ignore[attr-defined]
        if statuses[-1] != "RUNNING":
            break
        clock.advance_s(0.01)
    assert statuses[-1] == "FAILURE" and set(statuses[:-1]) == {"RUNNING"}
    # the last measurement came at most one camera period (1/15 s) before tick 50; lost 0.6 s after it
    assert 50 + 60 - 7 <= len(statuses) <= 50 + 61
    leaf = next(n for n in tree.nodes() if n.bt_type == "FollowTarget")  # type: ignore[attr-defined]
    assert leaf.failure_reason == "TARGET_LOST"
    assert np.all(robot.qd == 0.0)
