"""Forward and inverse kinematics: FK of random configurations, IK round trips, bad requests."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.geometry import pose_error
from bt_grasp.motion.kinematics import ArmKinematics, IKStatus, is_rigid_transform
from bt_grasp.robot_description import ARM_JOINTS, TCP_LINK
from tests.motion.conftest import HOME_Q


def test_model_is_the_six_arm_joints(kin: ArmKinematics) -> None:
    assert kin.model.nq == 6
    assert tuple(kin.model.names[1:]) == ARM_JOINTS
    assert TCP_LINK in kin.link_names


def test_fk_tcp_is_fk_link_tcp_and_rigid(kin: ArmKinematics) -> None:
    q = np.array([0.3, -1.2, 1.4, -1.0, -1.5, 0.4])
    T = kin.fk(q)
    assert is_rigid_transform(T)
    np.testing.assert_allclose(T, kin.fk_link(q, TCP_LINK))
    # the tcp is 80 mm beyond tool0 along tool0's z
    T_tool = kin.fk_link(q, "tool0")
    np.testing.assert_allclose(T[:3, 3], T_tool[:3, 3] + 0.08 * T_tool[:3, 2], atol=1e-12)


def test_fk_rejects_a_bad_configuration(kin: ArmKinematics) -> None:
    with pytest.raises(ValueError):
        kin.fk(np.array([0.0, np.nan, 0, 0, 0, 0]))
    with pytest.raises(KeyError):
        kin.fk_link(HOME_Q, "no_such_link")


def test_ik_reaches_random_reachable_poses(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(7)
    for _ in range(60):
        q_true = rng.uniform(-np.pi, np.pi, 6)
        q_true[2] = rng.uniform(-2.8, 2.8)
        T_goal = kin.fk(q_true)
        result = kin.ik(T_goal, HOME_Q, seeds=32, rng=rng)
        assert result.status is IKStatus.OK, result
        dp, dr = pose_error(kin.fk(result.q), T_goal)
        assert dp < 1e-4  # 0.1 mm
        assert np.rad2deg(dr) < 0.01
        assert kin.within_limits(result.q)


def test_ik_from_a_nearby_start_returns_the_nearby_solution(kin: ArmKinematics) -> None:
    q_true = HOME_Q + np.array([0.1, -0.05, 0.08, 0.1, -0.1, 0.2])
    result = kin.ik(kin.fk(q_true), HOME_Q)
    assert result.ok
    np.testing.assert_allclose(result.q, q_true, atol=1e-4)


def test_ik_solutions_are_distinct_and_sorted_by_distance(kin: ArmKinematics) -> None:
    T_goal = kin.fk(HOME_Q + 0.2)
    solutions, best = kin.ik_solutions(T_goal, HOME_Q, seeds=16, rng=np.random.default_rng(1))
    assert best.ok and len(solutions) >= 2
    distances = [np.linalg.norm(q - HOME_Q) for q in solutions]
    assert distances == sorted(distances)
    for q in solutions:
        assert pose_error(kin.fk(q), T_goal)[0] < 1e-4


def test_ik_far_away_pose_is_unreachable(kin: ArmKinematics) -> None:
    T_goal = np.eye(4)
    T_goal[:3, 3] = [2.0, 0.0, 0.3]
    result = kin.ik(T_goal, HOME_Q, rng=np.random.default_rng(0))
    assert result.status is IKStatus.UNREACHABLE


def test_ik_just_out_of_reach_is_unreachable(kin: ArmKinematics) -> None:
    T_goal = np.eye(4)
    T_goal[:3, 3] = [1.15, 0.0, 0.1]  # inside the crude reach bound, outside the real workspace
    result = kin.ik(T_goal, HOME_Q, seeds=8, rng=np.random.default_rng(0))
    assert result.status is IKStatus.UNREACHABLE
    assert result.position_error_m > 0.01


@pytest.mark.parametrize(
    "T_goal",
    [np.full((4, 4), np.nan), np.zeros((4, 4)), np.eye(3), np.diag([2.0, 1.0, 1.0, 1.0])],
)
def test_ik_bad_pose_is_invalid_input(kin: ArmKinematics, T_goal: np.ndarray) -> None:
    assert kin.ik(T_goal, HOME_Q).status is IKStatus.INVALID_INPUT


def test_ik_bad_current_configuration_is_invalid_input(kin: ArmKinematics) -> None:
    assert kin.ik(kin.fk(HOME_Q), np.array([np.nan] * 6)).status is IKStatus.INVALID_INPUT
    assert kin.ik(kin.fk(HOME_Q), np.zeros(5)).status is IKStatus.INVALID_INPUT


def test_ik_is_deterministic_for_a_seed(kin: ArmKinematics) -> None:
    T_goal = kin.fk(np.array([1.0, -0.5, 2.0, 0.3, 1.2, -2.0]))
    a = kin.ik(T_goal, HOME_Q, rng=np.random.default_rng(3))
    b = kin.ik(T_goal, HOME_Q, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a.q, b.q)
