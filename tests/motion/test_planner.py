"""Planning: collision-free paths, detours around obstacles, determinism, bad requests as values."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.geometry import make_T, pose_error
from bt_grasp.motion.collision import collision_checker
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.planner import PlannerOptions, PlanStatus, plan_to_joints, plan_to_pose
from bt_grasp.motion.planning_scene import Box, PlanningScene
from tests.motion.conftest import HOME_Q, TOP_DOWN_R

PILLAR = Box("pillar", (0.08, 0.08, 0.25), (0.47, 0.0, 0.125))


@pytest.fixture(scope="module")
def detour(kin: ArmKinematics, table_scene: PlanningScene) -> tuple[np.ndarray, np.ndarray, PlanningScene]:
    qa = kin.ik(make_T(TOP_DOWN_R, [0.45, -0.2, 0.08]), HOME_Q).q
    qb = kin.ik(make_T(TOP_DOWN_R, [0.45, 0.2, 0.08]), HOME_Q).q
    return qa, qb, table_scene.with_obstacles(PILLAR)


def test_plan_to_pose_reaches_the_pose(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    T_goal = make_T(TOP_DOWN_R, [0.5, 0.15, 0.12])
    result = plan_to_pose(HOME_Q, T_goal, table_scene)
    assert result.status is PlanStatus.OK, result.message
    np.testing.assert_array_equal(result.path[0], HOME_Q)
    dp, dr = pose_error(kin.fk(result.path[-1]), T_goal)
    assert dp < 1e-4 and dr < 1e-3
    assert result.ik_time_s > 0
    assert collision_checker(table_scene, 0.01).check_path(result.path, 0.005).ok


def test_obstacle_between_start_and_goal_forces_a_detour(detour: tuple) -> None:
    qa, qb, scene = detour
    checker = collision_checker(scene, 0.01)
    assert checker.is_valid(qa) and checker.is_valid(qb)
    assert not checker.check_path(np.stack([qa, qb]), 0.01).ok  # the straight line hits the pillar
    result = plan_to_joints(qa, qb, scene)
    assert result.status is PlanStatus.OK, result.message
    assert len(result.path) > 2
    np.testing.assert_allclose(result.path[-1], qb)
    assert checker.check_path(result.path, 0.005).ok  # re-checked finer than the planner's 0.01 rad


@pytest.mark.parametrize("planner", ["AORRTC", "BITstar"])
def test_other_planners_by_name(detour: tuple, planner: str) -> None:
    qa, qb, scene = detour
    result = plan_to_joints(qa, qb, scene, PlannerOptions(planner=planner))
    assert result.status is PlanStatus.OK, result.message
    assert result.planner == planner
    assert collision_checker(scene, 0.01).check_path(result.path, 0.01).ok


def test_same_seed_same_path_other_seed_other_path(detour: tuple) -> None:
    qa, qb, scene = detour
    a = plan_to_joints(qa, qb, scene, PlannerOptions(seed=5))
    b = plan_to_joints(qa, qb, scene, PlannerOptions(seed=5))
    c = plan_to_joints(qa, qb, scene, PlannerOptions(seed=6))
    assert a.ok and b.ok and c.ok
    np.testing.assert_array_equal(a.path, b.path)
    assert a.path.shape != c.path.shape or not np.array_equal(a.path, c.path)


def test_nan_pose_is_invalid_input(table_scene: PlanningScene) -> None:
    T = make_T(TOP_DOWN_R, [0.5, 0.0, 0.1])
    T[0, 3] = np.nan
    assert plan_to_pose(HOME_Q, T, table_scene).status is PlanStatus.INVALID_INPUT


def test_nan_start_is_invalid_input(table_scene: PlanningScene) -> None:
    result = plan_to_joints(np.full(6, np.nan), HOME_Q, table_scene)
    assert result.status is PlanStatus.INVALID_INPUT


@pytest.mark.parametrize("limit", [0.0, -1.0, float("nan")])
def test_bad_safety_limit_is_invalid_input(table_scene: PlanningScene, limit: float) -> None:
    result = plan_to_pose(HOME_Q, make_T(TOP_DOWN_R, [0.5, 0.0, 0.1]), table_scene,
                          PlannerOptions(safety_limit_s=limit))
    assert result.status is PlanStatus.INVALID_INPUT
    assert "safety_limit_s" in result.message


@pytest.mark.parametrize("budget", [0, -5])
def test_bad_budget_is_invalid_input(table_scene: PlanningScene, budget: int) -> None:
    result = plan_to_pose(HOME_Q, make_T(TOP_DOWN_R, [0.5, 0.0, 0.1]), table_scene,
                          PlannerOptions(max_state_checks=budget))
    assert result.status is PlanStatus.INVALID_INPUT
    assert "max_state_checks" in result.message


def test_unknown_planner_is_invalid_input(table_scene: PlanningScene) -> None:
    result = plan_to_joints(HOME_Q, HOME_Q + 0.1, table_scene, PlannerOptions(planner="FancyRRT"))
    assert result.status is PlanStatus.INVALID_INPUT
    assert "FancyRRT" in result.message and "RRTConnect" in result.message


def test_goal_pose_inside_the_table_is_goal_in_collision(table_scene: PlanningScene) -> None:
    result = plan_to_pose(HOME_Q, make_T(TOP_DOWN_R, [0.5, 0.0, -0.01]), table_scene)
    assert result.status is PlanStatus.GOAL_IN_COLLISION


def test_goal_configuration_in_collision(table_scene: PlanningScene) -> None:
    q_goal = HOME_Q.copy()
    q_goal[1] = -0.3
    assert plan_to_joints(HOME_Q, q_goal, table_scene).status is PlanStatus.GOAL_IN_COLLISION


def test_start_in_collision(table_scene: PlanningScene) -> None:
    q_start = HOME_Q.copy()
    q_start[1] = -0.3
    result = plan_to_pose(q_start, make_T(TOP_DOWN_R, [0.5, 0.0, 0.1]), table_scene)
    assert result.status is PlanStatus.START_IN_COLLISION
    assert "table" in result.message


def test_far_pose_is_ik_unreachable(table_scene: PlanningScene) -> None:
    result = plan_to_pose(HOME_Q, make_T(TOP_DOWN_R, [2.0, 0.0, 0.1]), table_scene)
    assert result.status is PlanStatus.IK_UNREACHABLE


def test_too_small_budget_is_budget_exhausted(detour: tuple) -> None:
    qa, qb, scene = detour
    result = plan_to_joints(qa, qb, scene, PlannerOptions(max_state_checks=20))
    assert result.status is PlanStatus.BUDGET_EXHAUSTED, result.message
    assert result.state_checks >= 20 and "20 state checks" in result.message


def test_the_search_ends_on_its_budget_not_the_clock(detour: tuple, monkeypatch: pytest.MonkeyPatch) -> None:
    """A machine ten times slower (every collision check delayed) plans exactly the same path."""
    import time

    from bt_grasp.motion.collision import CollisionChecker

    qa, qb, scene = detour
    options = PlannerOptions(seed=3)
    fast = plan_to_joints(qa, qb, scene, options)
    inner = CollisionChecker.in_collision

    def slow(self: CollisionChecker, q: np.ndarray) -> bool:
        end = time.perf_counter() + 3e-4  # busy, like a loaded core
        while time.perf_counter() < end:
            pass
        return inner(self, q)

    monkeypatch.setattr(CollisionChecker, "in_collision", slow)
    slowed = plan_to_joints(qa, qb, scene, options)
    assert fast.ok and slowed.ok
    assert slowed.planning_time_s > fast.planning_time_s
    assert fast.state_checks == slowed.state_checks
    np.testing.assert_array_equal(fast.path, slowed.path)


def test_the_safety_net_is_a_named_failure(detour: tuple) -> None:
    qa, qb, scene = detour
    result = plan_to_joints(qa, qb, scene, PlannerOptions(safety_limit_s=1e-6))
    assert result.status is PlanStatus.SAFETY_TIMEOUT, result.message
    assert "safety net" in result.message


def test_the_goal_set_checks_every_closed_form_solution(scene_config) -> None:  # type: ignore[no-untyped-def]
    """Bench problem 2: of the pose's 8 IK solutions the closest free one is the goal, whatever collides first."""
    from bt_grasp.bench.plan import make_problems
    from bt_grasp.motion.planner import default_planner

    problem = make_problems(scene_config, 3, seed=0)[2]
    scene = problem.scene(scene_config)
    planner = default_planner()
    checker = planner.checker(scene, 0.01)
    every = planner.kin.closed_form_ik(problem.T_base_tcp_goal, problem.q_start)
    assert every is not None and len(every) == 8
    free = [q for q in every if checker.is_valid(q)]
    assert 0 < len(free) < 8 and not checker.is_valid(every[0])  # the closest solution collides
    found = planner.goal_set(problem.q_start, problem.T_base_tcp_goal, checker, PlannerOptions(max_goal_configs=1))
    assert found.solutions == 8 and found.seeds_used == 0
    assert len(found.goals) == 1 and np.array_equal(found.goals[0], free[0])
    result = plan_to_pose(problem.q_start, problem.T_base_tcp_goal, scene)
    assert result.ok, result.message
    assert collision_checker(scene, 0.01).check_path(result.path, 0.005).ok


def test_seeded_ik_goal_sets_go_on_past_colliding_solutions(scene_config, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Without a closed form (a non-UR arm), seeding goes on: bench problem 2's first three solutions collide."""
    from bt_grasp.bench.plan import make_problems
    from bt_grasp.motion.kinematics import ArmKinematics
    from bt_grasp.motion.planner import default_planner

    monkeypatch.setattr(ArmKinematics, "closed_form_ik", lambda self, T, q: None)
    problem = make_problems(scene_config, 3, seed=0)[2]
    scene = problem.scene(scene_config)
    planner = default_planner()
    options = PlannerOptions(max_goal_configs=1)
    found = planner.goal_set(problem.q_start, problem.T_base_tcp_goal, planner.checker(scene, 0.01), options)
    assert found.solutions == 4 and len(found.goals) == 1 and found.seeds_used > 1  # stopped at the first free one
    result = plan_to_pose(problem.q_start, problem.T_base_tcp_goal, scene)
    assert result.ok, result.message
    assert collision_checker(scene, 0.01).check_path(result.path, 0.005).ok


def test_a_pose_whose_every_ik_solution_collides_is_goal_in_collision(scene_config) -> None:  # type: ignore[no-untyped-def]
    """Bench problem 18: all eight solutions of the UR5 collide; the closed form says so."""
    from bt_grasp.bench.plan import make_problems

    problem = make_problems(scene_config, 19, seed=0)[18]
    result = plan_to_pose(problem.q_start, problem.T_base_tcp_goal, problem.scene(scene_config))
    assert result.status is PlanStatus.GOAL_IN_COLLISION
    assert "all 8 IK solutions (closed form: every solution) collide" in result.message
