"""Gripper leaves, tick by tick, with a stand-in robot (fingers move 5 mm per tick)."""

from __future__ import annotations

from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.tree.loader import load_tree_from_string

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence>
      <Grasp width="{w}"/>
      <IsGrasped/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _run(robot: FakeRobot, ticks: int) -> tuple[list[str], object]:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, robot_registry(), clock=clock)
    cell = fake_cell(robot, clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    statuses = []
    for _ in range(ticks):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return statuses, tree


def test_grasp_on_object_succeeds_and_reports_width() -> None:
    # ticks 1..7: the fingers close from 85 mm to the 50 mm object (5 mm per tick) -> RUNNING
    # then 5 ticks with the width unchanged -> settled -> Grasp SUCCESS, IsGrasped SUCCESS on the same tick
    robot = FakeRobot(object_width_m=0.05)
    statuses, tree = _run(robot, 40)
    assert statuses[-1] == "SUCCESS"
    assert statuses[:-1] == ["RUNNING"] * (len(statuses) - 1)
    assert 12 <= len(statuses) <= 14
    assert abs(tree.blackboard_values()["w"] - 0.05) < 1e-9


def test_grasp_on_nothing_fails_with_grasp_empty() -> None:
    # the fingers close to 0 in 17 ticks, settle for 5 more: FAILURE with GRASP_EMPTY on the blackboard
    robot = FakeRobot(object_width_m=0.0)
    statuses, tree = _run(robot, 60)
    assert statuses[-1] == "FAILURE"
    values = tree.blackboard_values()
    assert values["failure_reason"] == "GRASP_EMPTY"
    assert values["failed_leaf"] == "Grasp"
    grasp = tree.find("Grasp")
    assert "nothing held" in grasp.feedback_message
