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
    # tick 1: the fingers still at 85 mm (the width has not changed since the command: still 1) -> RUNNING
    # ticks 2..8: they close 5 mm per tick to the 50 mm object (still 0) -> RUNNING
    # ticks 9..13: the width unchanged (still 1..5) -> settled on tick 13: Grasp SUCCESS, IsGrasped SUCCESS
    robot = FakeRobot(object_width_m=0.05)
    statuses, tree = _run(robot, 40)
    assert statuses == ["RUNNING"] * 12 + ["SUCCESS"]
    assert abs(tree.blackboard_values()["w"] - 0.05) < 1e-9


def test_grasp_on_nothing_fails_with_grasp_empty() -> None:
    # the fingers close to 0 on ticks 2..18 (17 x 5 mm), settle on ticks 19..23: FAILURE with GRASP_EMPTY
    robot = FakeRobot(object_width_m=0.0)
    statuses, tree = _run(robot, 60)
    assert statuses == ["RUNNING"] * 22 + ["FAILURE"]
    values = tree.blackboard_values()
    assert values["failure_reason"] == "GRASP_EMPTY"
    assert values["failed_leaf"] == "Grasp"
    grasp = tree.find("Grasp")
    assert "nothing held" in grasp.feedback_message
