"""PlanGrasp and Approach, tick by tick, with stand-in kinematics and planner (no simulator).

PlanGrasp tries one ranked candidate per tick (IK of pre-grasp and grasp, the approach plan, then the straight
descent from the plan's end) and hands
Approach a GraspPlan; Approach executes its path and plans again only when the arm moved or the scene changed.
"""

from __future__ import annotations

import numpy as np
import pytest
from behaviour_fakes import FakeKinematics, FakePlanner, FakeRobot, detection, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.grasp_plan import GraspPlan
from bt_grasp.clock import ManualClock
from bt_grasp.motion.cartesian import CartesianStatus
from bt_grasp.motion.planner import PlanStatus
from bt_grasp.perception.results import Detection
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string

PLAN = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <PlanGrasp target="{target}" objects="{objects}" grasp="{grasp}" skip="{skip}"/>
  </BehaviorTree>
</root>
"""

APPROACH = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence>
      <PlanGrasp target="{target}" objects="{objects}" grasp="{grasp}"/>
      <Approach grasp="{grasp}" target="{target}" objects="{objects}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _setup(xml: str, kin: FakeKinematics, planner: FakePlanner) -> tuple[LoadedTree, Cell, FakeRobot]:
    clock, robot = ManualClock(), FakeRobot()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = fake_cell(robot, clock)
    cell.kinematics, cell.planner = kin, planner
    for node in tree.nodes():
        node.setup(cell=cell)
    tree.root_blackboard.set("target", detection())
    tree.root_blackboard.set("objects", (detection(), detection(x_m=0.3, label="blue")))
    tree.root_blackboard.set("skip", 0)
    return tree, cell, robot


def _ticks(tree: LoadedTree, n: int) -> list[str]:
    out = []
    for _ in range(n):
        out.append(tree.tick().value)
        if out[-1] != "RUNNING":
            break
    return out


def test_first_candidate_plans_in_the_first_tick() -> None:
    # tick 1: candidates ranked, candidate 0's IK and plan succeed -> SUCCESS with its GraspPlan
    tree, _, robot = _setup(PLAN, FakeKinematics(), FakePlanner())
    assert _ticks(tree, 5) == ["SUCCESS"]
    plan = tree.root_blackboard.get("grasp")
    assert isinstance(plan, GraspPlan)
    assert np.allclose(plan.q_start, robot.q) and plan.approach_path.shape == (2, 6)
    assert plan.target == detection()


def test_one_candidate_per_tick_until_one_is_reachable() -> None:
    # tick 1: candidate 0's pre-grasp IK fails -> RUNNING
    # tick 2: candidate 1's IK succeeds twice, its plan fails (NO_PATH) -> RUNNING
    # tick 3: candidate 2 plans -> SUCCESS
    planner = FakePlanner((PlanStatus.NO_PATH,))
    tree, _, _ = _setup(PLAN, FakeKinematics(failures=1), planner)
    assert _ticks(tree, 10) == ["RUNNING", "RUNNING", "SUCCESS"]
    assert len(planner.pose_calls) == 2
    assert "candidate 2" in tree.find("PlanGrasp").feedback_message


def test_a_candidate_that_fails_is_named_once() -> None:
    """Issue 43, finding 8: the feedback read "candidate 0: candidate 0: pre-grasp unreachable"."""
    tree, _, _ = _setup(PLAN, FakeKinematics(failures=1), FakePlanner())
    assert _ticks(tree, 1) == ["RUNNING"]
    message = tree.find("PlanGrasp").feedback_message
    assert message.startswith("candidate 0: ") and message.count("candidate 0") == 1, message


def _counts() -> tuple[int, int]:
    """The 5 cm cube's footprint grasps (four), then how many grasps sampled from its fitted box are not near-same
    as one of them: the sampling draws from the run's GRASPS stream (``bt_grasp.seeds``; ``fake_cell``'s seed 0),
    so the count is the draw's, computed here with the very calls PlanGrasp makes."""
    from bt_grasp.perception.antipodal import AntipodalSettings, near_same, rank_grasps, sampled_grasps
    from bt_grasp.perception.config import GraspSettings
    from bt_grasp.seeds import RunSeeds, Stream

    seed = RunSeeds(0).integer(Stream.GRASPS)
    target, objects, settings = detection(), (detection(), detection(x_m=0.3, label="blue")), GraspSettings()
    ranked = rank_grasps(target, objects, settings, seed=seed).candidates
    more = sampled_grasps(target, objects, AntipodalSettings(pregrasp_offset_m=settings.pregrasp_offset_m), seed=seed)
    return len(ranked), len([c for c in more if not any(near_same(c, r) for r in ranked)])


FOOTPRINT, SAMPLED = _counts()


def test_the_cube_has_four_footprint_grasps_and_some_sampled_ones() -> None:
    assert FOOTPRINT == 4 and SAMPLED >= 1


@pytest.mark.parametrize(
    ("ik_failures", "statuses", "tried", "reason"),
    [
        # every pre-grasp unreachable: no sampled grasp is reachable either, so only the footprint's are tried
        (99, (), FOOTPRINT, "IK_UNREACHABLE"),
        (0, (PlanStatus.NO_PATH,) * 99, FOOTPRINT + SAMPLED, "PLAN_FAILED"),  # reachable, but no path to any
        (0, (PlanStatus.GOAL_IN_COLLISION,) * 99, FOOTPRINT + SAMPLED, "PLAN_FAILED"),  # every pre-grasp collides
        (0, (PlanStatus.IK_UNREACHABLE,) * 99, FOOTPRINT + SAMPLED, "IK_UNREACHABLE"),  # the planner's IK fails
    ],
)
def test_no_candidate_reachable_fails_after_trying_each(
    ik_failures: int, statuses: tuple[PlanStatus, ...], tried: int, reason: str
) -> None:
    # one candidate per tick: RUNNING while candidates remain, then FAILURE with the last reason
    tree, _, _ = _setup(PLAN, FakeKinematics(failures=ik_failures), FakePlanner(statuses))
    assert _ticks(tree, 20) == ["RUNNING"] * (tried - 1) + ["FAILURE"]
    values = tree.blackboard_values()
    assert values["failure_reason"] == reason and values["failed_leaf"] == "PlanGrasp"


def test_when_every_footprint_grasp_is_blocked_the_sampled_grasps_are_tried_next() -> None:
    # ticks 1-4: the footprint's four grasps have no path -> RUNNING; after the fourth, the grasps sampled from
    # the cloud that are not near-same as one of them are added; tick 5: the first of them plans -> SUCCESS
    from bt_grasp.perception.antipodal import near_same, rank_grasps

    tree, _, _ = _setup(PLAN, FakeKinematics(), FakePlanner((PlanStatus.NO_PATH,) * FOOTPRINT))
    assert _ticks(tree, 20) == ["RUNNING"] * FOOTPRINT + ["SUCCESS"]
    plan = tree.root_blackboard.get("grasp")
    assert isinstance(plan, GraspPlan)
    footprint = rank_grasps(detection(), tree.root_blackboard.get("objects")).candidates
    assert len(footprint) == FOOTPRINT and not any(near_same(plan.candidate, c) for c in footprint)
    assert f"candidate {FOOTPRINT} of {FOOTPRINT + SAMPLED}" in tree.find("PlanGrasp").feedback_message


def test_a_candidate_whose_straight_descent_is_blocked_is_passed_over() -> None:
    # tick 1: candidate 0 plans to its pre-grasp pose, but the straight descent from there collides with a
    #         neighbour -> RUNNING (not SUCCESS: Approach would only find it blocked later)
    # tick 2: candidate 1 plans and descends freely -> SUCCESS, with both paths in the GraspPlan
    planner = FakePlanner(descents=(CartesianStatus.COLLISION,))
    tree, _, _ = _setup(PLAN, FakeKinematics(), planner)
    assert _ticks(tree, 10) == ["RUNNING", "SUCCESS"]
    assert len(planner.pose_calls) == 2 and len(planner.line_calls) == 2
    plan = tree.root_blackboard.get("grasp")
    assert isinstance(plan, GraspPlan) and plan.descent_path is not None
    assert np.allclose(planner.line_calls[1], plan.approach_path[-1])  # the descent starts where the path ends
    assert np.allclose(plan.descent_path[0], plan.approach_path[-1])
    assert "candidate 1" in tree.find("PlanGrasp").feedback_message


def test_every_descent_blocked_fails_plan_failed_naming_the_descent() -> None:
    # the ten candidates' descents all collide: RUNNING x9, then FAILURE (PLAN_FAILED, as every planning
    # failure of PlanGrasp other than IK) whose message says the descent was blocked
    planner = FakePlanner(descents=(CartesianStatus.COLLISION,) * (FOOTPRINT + SAMPLED))
    tree, _, _ = _setup(PLAN, FakeKinematics(), planner)
    assert _ticks(tree, 20) == ["RUNNING"] * (FOOTPRINT + SAMPLED - 1) + ["FAILURE"]
    values = tree.blackboard_values()
    assert values["failure_reason"] == "PLAN_FAILED" and values["failed_leaf"] == "PlanGrasp"
    assert "straight descent fails (collision)" in tree.find("PlanGrasp").feedback_message


def test_no_target_and_nothing_graspable() -> None:
    tree, _, _ = _setup(PLAN, FakeKinematics(), FakePlanner())
    tree.root_blackboard.set("target", detection(size_m=0.2))  # wider than the open gripper
    assert _ticks(tree, 3) == ["FAILURE"]
    assert tree.blackboard_values()["failure_reason"] == "NOTHING_TO_GRASP"


def test_skip_past_every_candidate_fails_at_once() -> None:
    tree, _, _ = _setup(PLAN, FakeKinematics(), FakePlanner())
    tree.root_blackboard.set("skip", FOOTPRINT + SAMPLED)
    assert _ticks(tree, 3) == ["FAILURE"]
    assert tree.blackboard_values()["failure_reason"] == "PLAN_FAILED"


def test_skip_past_the_footprint_s_grasps_goes_on_to_the_sampled_ones() -> None:
    tree, _, _ = _setup(PLAN, FakeKinematics(), FakePlanner())
    tree.root_blackboard.set("skip", FOOTPRINT + 1)
    assert _ticks(tree, 3) == ["SUCCESS"]
    assert f"candidate 0 of {FOOTPRINT + SAMPLED}" in tree.find("PlanGrasp").feedback_message


def test_approach_executes_the_planned_path_without_planning_again() -> None:
    # tick 1: PlanGrasp SUCCESS (one plan), Approach starts: its first segment is the plan's path
    planner = FakePlanner()
    tree, _, _ = _setup(APPROACH, FakeKinematics(), planner)
    assert tree.tick().value == "RUNNING"
    assert len(planner.pose_calls) == 1
    assert tree.find("Approach").feedback_message == "to pre-grasp"


ONLY_APPROACH = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Approach grasp="{grasp}" target="{target}" objects="{objects}"/>
  </BehaviorTree>
</root>
"""


def _plan_then_approach(objects_later: tuple[Detection, ...] | None, arm_moves_by: float) -> FakePlanner:
    """Plan with PlanGrasp, then (optionally) move the arm or change the objects, then start Approach."""
    planner = FakePlanner()
    plan_tree, cell, robot = _setup(PLAN, FakeKinematics(), planner)
    assert _ticks(plan_tree, 2) == ["SUCCESS"]
    robot.q = robot.q + arm_moves_by
    approach = load_tree_from_string(ONLY_APPROACH, robot_registry(), clock=ManualClock())
    for node in approach.nodes():
        node.setup(cell=cell)
    approach.root_blackboard.set("grasp", plan_tree.root_blackboard.get("grasp"))
    approach.root_blackboard.set("target", plan_tree.root_blackboard.get("target"))
    objects = plan_tree.root_blackboard.get("objects") if objects_later is None else objects_later
    approach.root_blackboard.set("objects", objects)
    assert approach.tick().value == "RUNNING"
    return planner


def test_approach_reuses_the_plan_when_nothing_changed() -> None:
    planner = _plan_then_approach(None, 0.0)
    assert len(planner.pose_calls) == 1


def test_approach_plans_again_when_the_arm_moved() -> None:
    planner = _plan_then_approach(None, 0.01)
    assert len(planner.pose_calls) == 2 and np.allclose(planner.pose_calls[-1], np.full(6, 0.01))


def test_approach_plans_again_when_the_scene_changed() -> None:
    planner = _plan_then_approach((detection(), detection(x_m=0.35, label="blue")), 0.0)
    assert len(planner.pose_calls) == 2


def test_approach_without_a_grasp_fails_bad_input() -> None:
    tree = load_tree_from_string(ONLY_APPROACH, robot_registry(), clock=ManualClock())
    clock, robot = ManualClock(), FakeRobot()
    cell = fake_cell(robot, clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    assert tree.tick().value == "FAILURE"
    assert tree.blackboard_values()["failure_reason"] == "BAD_INPUT"
