"""Closed-form UR IK: every solution of a pose, checked against the model's forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.motion.analytic_ik import ur_analytic_ik
from bt_grasp.motion.kinematics import ArmKinematics, default_kinematics


@pytest.fixture(scope="module")
def kin() -> ArmKinematics:
    return default_kinematics()


def test_the_ur5_model_has_a_verified_closed_form(kin: ArmKinematics) -> None:
    assert kin.has_closed_form_ik


def test_every_returned_solution_reaches_the_pose_and_the_original_is_among_them(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(3)
    counts = []
    for _ in range(300):
        q = rng.uniform(-np.pi, np.pi, 6)
        q[2] = rng.uniform(-3.0, 3.0)
        T = kin.fk(q)
        solutions = kin.closed_form_ik(T, q)
        assert solutions is not None and 1 <= len(solutions) <= 8
        for s in solutions:
            np.testing.assert_allclose(kin.fk(s), T, atol=1e-7)
            assert kin.within_limits(s)
        assert np.max(np.abs(solutions[0] - q)) < 1e-6  # the closest is q itself (whole turns towards q)
        for i, a in enumerate(solutions):  # distinct
            for b in solutions[i + 1:]:
                assert np.max(np.abs(a - b)) > 1e-6
        counts.append(len(solutions))
    assert max(counts) == 8  # a generic pose has all eight


def test_the_dls_ik_finds_nothing_the_closed_form_misses(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(11)
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.4])
    T = kin.fk(q)
    closed = kin.closed_form_ik(T, q)
    assert closed is not None
    numeric, _ = kin.ik_solutions(T, q, seeds=60, rng=rng)
    def turns_apart(a: np.ndarray, b: np.ndarray) -> float:  # whole turns of a joint are the same geometry
        return float(np.max(np.abs(np.mod(a - b + np.pi, 2 * np.pi) - np.pi)))

    assert len(numeric) >= 6
    for s in numeric:
        assert min(turns_apart(s, c) for c in closed) < 1e-4


def test_a_pose_out_of_reach_has_no_solution(kin: ArmKinematics) -> None:
    T = np.eye(4)
    T[:3, 3] = [1.2, 0.0, 0.3]
    assert kin.closed_form_ik(T, np.zeros(6)) == []


def test_the_wrist_singularity_keeps_the_reference_last_joint(kin: ArmKinematics) -> None:
    q = np.array([0.2, -1.0, 1.2, -0.5, 0.0, 0.7])  # theta5 = 0: wrist 1 and 3 axes aligned
    q_ref = q.copy()
    q_ref[5] = 1.1
    solutions = kin.closed_form_ik(kin.fk(q), q_ref)
    assert solutions
    for s in solutions:
        np.testing.assert_allclose(kin.fk(s), kin.fk(q), atol=1e-7)
    assert any(abs(s[5] - 1.1) < 1e-9 for s in solutions)


def test_a_model_that_is_not_ur_shaped_has_no_closed_form() -> None:
    def fk(q: np.ndarray) -> np.ndarray:  # a planar chain: nothing like a UR arm
        T = np.eye(4)
        T[0, 3] = float(np.sum(np.cos(np.cumsum(q))))
        T[1, 3] = float(np.sum(np.sin(np.cumsum(q))))
        return T

    offsets = [np.array([0.0, 0.0, 0.1])] * 6
    assert ur_analytic_ik(fk, offsets, np.array([0.0, 0.1, 0.0])) is None


def test_a_pose_whose_rotation_is_slightly_off_orthonormal_is_solved(kin: ArmKinematics) -> None:
    """A grasp frame built from a measured, slightly tilted box: the y axis not quite orthogonal to z."""
    q = np.array([0.1, -1.3, 1.5, -1.8, -1.57, 0.2])
    T = kin.fk(q)
    T[:3, 1] += np.array([0.0, 0.0, 2e-5])  # still a "rigid transform" at 1e-4, as plan_to_pose accepts
    solutions = kin.closed_form_ik(T, q)
    assert solutions and np.max(np.abs(solutions[0] - q)) < 1e-4
