"""Time parametrisation: limits hold at every sample, waypoints are reached, paths are followed."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.motion.trajectory import MotionLimits, Trajectory, TrajectoryError, time_parametrize
from bt_grasp.robot_description import arm_joint_limits
from tests.motion.conftest import HOME_Q


def _assert_within_limits(traj: Trajectory, limits: MotionLimits) -> None:
    v, a, j = limits.arrays()
    assert np.all(np.abs(traj.qd) <= v + 1e-9)
    assert np.all(np.abs(traj.qdd) <= a + 1e-9)
    dt = np.diff(traj.times_s)[:, None]
    # acceleration is piecewise linear in time, so its finite differences bound the jerk exactly
    assert np.all(np.abs(np.diff(traj.qdd, axis=0)) / dt <= j * (1 + 1e-6))
    # and velocity/position are consistent with the samples (no jumps)
    assert np.all(np.abs(np.diff(traj.q, axis=0)) <= v * dt + 1e-9)


@pytest.mark.parametrize("blend", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_limits_hold_at_every_sample(seed: int, blend: bool) -> None:
    rng = np.random.default_rng(seed)
    path = HOME_Q + np.cumsum(rng.uniform(-0.6, 0.6, (6, 6)), axis=0)
    limits = MotionLimits()
    traj = time_parametrize(path, limits, blend=blend)
    _assert_within_limits(traj, limits)
    np.testing.assert_array_equal(traj.q[0], path[0])
    np.testing.assert_array_equal(traj.q[-1], path[-1])
    assert np.all(traj.qd[[0, -1]] == 0)
    np.testing.assert_allclose(np.diff(traj.times_s)[:-1], 0.01, atol=1e-12)  # 100 Hz
    assert traj.compute_time_s < 0.05


def test_custom_limits_are_respected_and_slower() -> None:
    path = np.stack([HOME_Q, HOME_Q + 0.8])
    fast = time_parametrize(path)
    slow_limits = MotionLimits(0.3, 1.0, 5.0)
    slow = time_parametrize(path, slow_limits)
    _assert_within_limits(slow, slow_limits)
    assert slow.duration_s > fast.duration_s
    assert MotionLimits().scaled(0.5).max_acceleration_rad_s2 == pytest.approx(2.5 * 0.25)


def test_velocity_is_clipped_to_the_urdf() -> None:
    v, _, _ = MotionLimits(max_velocity_rad_s=100.0).arrays()
    np.testing.assert_array_equal(v, arm_joint_limits().velocity_rad_s)


def test_rest_to_rest_segments_follow_the_straight_joint_line() -> None:
    path = np.stack([HOME_Q, HOME_Q + np.array([0.5, -0.2, 0.3, 0.0, 0.1, -0.4]), HOME_Q])
    traj = time_parametrize(path)
    for q in traj.q:  # every sample lies on one of the two segments
        distances = []
        for a, b in ((path[0], path[1]), (path[1], path[2])):
            s = np.clip(np.dot(q - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
            distances.append(np.linalg.norm(a + s * (b - a) - q))
        assert min(distances) < 1e-9
    assert traj.max_path_deviation_rad == 0.0


def test_blending_a_dense_line_is_faster_than_stopping() -> None:
    line = np.linspace(HOME_Q, HOME_Q + 0.3, 30)
    stop = time_parametrize(line)
    blend = time_parametrize(line, blend=True)
    assert blend.duration_s < 0.5 * stop.duration_s
    assert blend.max_path_deviation_rad < 1e-3


def test_single_point_path_is_a_hold() -> None:
    traj = time_parametrize(HOME_Q[None, :])
    assert traj.duration_s == 0.0
    np.testing.assert_array_equal(traj.sample(1.0)[0], HOME_Q)


def test_sample_interpolates_and_holds_after_the_end() -> None:
    traj = time_parametrize(np.stack([HOME_Q, HOME_Q + 0.2]))
    q_mid, _, _ = traj.sample(0.005)
    assert np.all(q_mid >= traj.q[0] - 1e-12) and np.all(q_mid <= traj.q[1] + 1e-12)
    np.testing.assert_array_equal(traj.sample(traj.duration_s + 5)[0], HOME_Q + 0.2)


@pytest.mark.parametrize("bad", [np.zeros((3, 5)), np.full((2, 6), np.nan), np.zeros((0, 6))])
def test_bad_path_raises(bad: np.ndarray) -> None:
    with pytest.raises(TrajectoryError):
        time_parametrize(bad)


def test_bad_limits_raise() -> None:
    with pytest.raises(ValueError):
        MotionLimits(max_jerk_rad_s3=0.0)


def _reference_sample(traj: Trajectory, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The interpolation as first written (searchsorted, q, qd and qdd one by one): the executor's targets."""
    t = min(max(float(t_s), 0.0), traj.duration_s)
    k = min(max(int(np.searchsorted(traj.times_s, t, side="right")) - 1, 0), len(traj.times_s) - 1)
    if k == len(traj.times_s) - 1:
        return traj.q[k], traj.qd[k], traj.qdd[k]
    dt = traj.times_s[k + 1] - traj.times_s[k]
    w = (t - traj.times_s[k]) / dt if dt > 0 else 0.0
    return tuple(a[k] + w * (a[k + 1] - a[k]) for a in (traj.q, traj.qd, traj.qdd))  # type: ignore[return-value]


@pytest.mark.parametrize("blend", [False, True])
def test_sample_is_bit_for_bit_the_interpolation_of_each_array(blend: bool) -> None:
    # issue 27 interpolates q, qd and qdd side by side in one array: every commanded target must stay the same
    rng = np.random.default_rng(5)
    traj = time_parametrize(HOME_Q + np.cumsum(rng.uniform(-0.4, 0.4, (5, 6)), axis=0), blend=blend)
    times = [*rng.uniform(-0.1, traj.duration_s + 0.1, 300), *traj.times_s, 0.0, traj.duration_s, 1e-12]
    for t in times:
        for got, want in zip(traj.sample(float(t)), _reference_sample(traj, float(t)), strict=True):
            assert got.tobytes() == np.asarray(want).tobytes()
    q, _, _ = traj.sample(0.0)
    q[:] = 99.0  # a sample is the caller's own array: the trajectory is unchanged
    assert traj.sample(0.0)[0][0] != 99.0 and traj.q[0][0] != 99.0


def test_the_deviation_is_the_largest_distance_from_the_polyline() -> None:
    line = np.linspace(HOME_Q, HOME_Q + 0.3, 12) + np.random.default_rng(2).uniform(-0.02, 0.02, (12, 6))
    traj = time_parametrize(line, blend=True)
    a, b = traj.waypoints[:-1], traj.waypoints[1:]
    worst = 0.0
    for q in traj.q:
        s = np.clip(np.einsum("ij,ij->i", q - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0.0, 1.0)
        worst = max(worst, float(np.min(np.linalg.norm(a + s[:, None] * (b - a) - q, axis=1))))
    assert traj.max_path_deviation_rad == pytest.approx(worst, rel=1e-12)
    assert traj.max_path_deviation_rad > 0.0
