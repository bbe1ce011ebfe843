"""The shipped recovery tree's planning-failure branch, driven by a truly infeasible goal (no simulator).

The target stands 1.6 m from the robot base, beyond the UR5's proven reach bound: the real kinematics and
planner answer ``IK_UNREACHABLE`` for every grasp candidate (an infeasible goal, not a spent budget), PlanGrasp
fails with that reason, and the shipped ``Recover`` subtree of ``trees/pick_with_recovery.xml`` takes its
``next_candidate_ik`` branch (``skip += 1``), not the timeout or re-home branches.
"""

from __future__ import annotations

from pathlib import Path

from behaviour_fakes import FakeRobot, detection, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.motion.planner import PlanStatus, default_planner
from bt_grasp.motion.planning_scene import PlanningScene
from bt_grasp.tree.loader import load_tree_from_string

SHIPPED = Path(__file__).resolve().parents[2] / "trees" / "pick_with_recovery.xml"

PROBE = """
  <BehaviorTree ID="Probe">
    <Sequence>
      <Script code="skip := 0"/>
      <Fallback>
        <PlanGrasp target="{target}" objects="{objects}" grasp="{grasp}" skip="{skip}"/>
        <ForceFailure><SubTree ID="Recover" _autoremap="true"/></ForceFailure>
      </Fallback>
    </Sequence>
  </BehaviorTree>
</root>"""


def test_an_unreachable_target_takes_the_next_candidate_branch() -> None:
    text = SHIPPED.read_text().replace('main_tree_to_execute="PickWithRecovery"', 'main_tree_to_execute="Probe"')
    text = text.replace("</root>", PROBE)
    clock, robot = ManualClock(), FakeRobot()
    tree = load_tree_from_string(text, robot_registry(), clock=clock)
    cell = fake_cell(robot, clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    far = detection(x_m=1.6)
    tree.root_blackboard.set("target", far)
    tree.root_blackboard.set("objects", (far,))
    statuses = []
    for _ in range(40):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
    assert statuses[-1] == "FAILURE"  # the probe ends after one recovery
    assert tree.root_blackboard.get("failure_reason") == "IK_UNREACHABLE"
    # skip += 1 happens only in next_candidate (needs PLAN_FAILED), next_candidate_ik (IK_UNREACHABLE) and
    # next_candidate_blocked (COLLISION); the reason is IK_UNREACHABLE, so the IK branch ran
    assert tree.root_blackboard.get("skip") == 1
    assert len(statuses) < 40


def test_the_planner_calls_such_a_goal_unreachable_not_a_spent_budget() -> None:
    import numpy as np

    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = [1.6, 0.0, 0.1]
    result = default_planner().plan_to_pose(np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0]), T, PlanningScene())
    assert result.status is PlanStatus.IK_UNREACHABLE
    assert "beyond the arm's reach" in result.message
