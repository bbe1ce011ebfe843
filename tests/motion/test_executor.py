"""The executor against a stand-in robot: one control period per update, tracking, settling, cancel."""

from __future__ import annotations

import numpy as np

from bt_grasp.clock import ManualClock
from bt_grasp.motion.executor import ExecFailure, ExecStatus, TrajectoryExecutor
from bt_grasp.motion.trajectory import time_parametrize
from tests.motion.conftest import HOME_Q


class FakeRobot:
    """A first-order joint servo (time constant ``tau_s``) that may be blocked (a stall)."""

    def __init__(self, q: np.ndarray, tau_s: float = 0.01) -> None:
        self.q = q.astype(float).copy()
        self.qd = np.zeros(6)
        self.target = self.q.copy()
        self.tau_s = tau_s
        self.blocked = False
        self.commands = 0

    joint_names = ("a", "b", "c", "d", "e", "f")

    def joint_positions(self) -> np.ndarray:
        return self.q.copy()

    def joint_velocities(self) -> np.ndarray:
        return self.qd.copy()

    def set_joint_targets(self, q_rad: np.ndarray, qd_rad_s: np.ndarray | None = None) -> None:
        self.target = np.asarray(q_rad, dtype=float).copy()
        self.commands += 1

    def step(self, dt: float) -> None:
        if self.blocked:
            self.qd[:] = 0
            return
        new = self.q + (self.target - self.q) * min(1.0, dt / self.tau_s)
        self.qd = (new - self.q) / dt
        self.q = new

    def open_gripper(self) -> None: ...
    def close_gripper(self, force_n: float | None = None) -> None: ...
    def gripper_width_m(self) -> float:
        return 0.085
    def gripper_target_width_m(self) -> float:
        return 0.085


def _run(executor: TrajectoryExecutor, robot: FakeRobot, clock: ManualClock, max_ticks: int = 2000,
         block_at_s: float | None = None) -> tuple[ExecStatus, int]:
    executor.start()
    for tick in range(max_ticks):
        if block_at_s is not None and clock.now_s() >= block_at_s:
            robot.blocked = True
        for _ in range(5):  # the caller steps physics between updates
            robot.step(0.002)
            clock.advance_s(0.002)
        status = executor.update()
        if status is not ExecStatus.RUNNING:
            return status, tick + 1
    return executor.status, max_ticks


def test_tracks_the_trajectory_and_settles_on_the_goal() -> None:
    goal = HOME_Q + np.array([0.4, -0.2, 0.3, 0.1, 0.0, -0.3])
    traj = time_parametrize(np.stack([HOME_Q, goal]))
    robot, clock = FakeRobot(HOME_Q), ManualClock()
    executor = TrajectoryExecutor(robot, traj, clock)
    assert executor.status is ExecStatus.IDLE
    status, ticks = _run(executor, robot, clock)
    assert status is ExecStatus.SUCCEEDED
    assert np.max(np.abs(robot.q - goal)) < 1e-3
    assert ticks >= round(traj.duration_s * 100)  # one control period per update, no loops inside
    assert executor.max_tracking_error_rad < 0.05
    assert executor.update() is ExecStatus.SUCCEEDED  # stays done


def test_a_stall_fails_with_tracking_error_and_holds() -> None:
    traj = time_parametrize(np.stack([HOME_Q, HOME_Q + 1.0]))
    robot, clock = FakeRobot(HOME_Q), ManualClock()
    executor = TrajectoryExecutor(robot, traj, clock)
    status, _ = _run(executor, robot, clock, block_at_s=0.5)
    assert status is ExecStatus.FAILED
    assert executor.reason is ExecFailure.TRACKING_ERROR
    np.testing.assert_allclose(robot.target, robot.q)  # holds where it stopped


def test_a_slow_arm_times_out_settling() -> None:
    traj = time_parametrize(np.stack([HOME_Q, HOME_Q + 0.05]))
    robot, clock = FakeRobot(HOME_Q, tau_s=5.0), ManualClock()
    executor = TrajectoryExecutor(robot, traj, clock)
    status, _ = _run(executor, robot, clock)
    assert status is ExecStatus.FAILED
    assert executor.reason is ExecFailure.SETTLE_TIMEOUT


def test_cancel_holds_the_current_position() -> None:
    traj = time_parametrize(np.stack([HOME_Q, HOME_Q + 1.0]))
    robot, clock = FakeRobot(HOME_Q), ManualClock()
    executor = TrajectoryExecutor(robot, traj, clock)
    executor.start()
    for _ in range(30):
        robot.step(0.01)
        clock.advance_s(0.01)
        executor.update()
    executor.cancel()
    assert executor.status is ExecStatus.CANCELLED
    np.testing.assert_allclose(robot.target, robot.q)
    assert executor.update() is ExecStatus.CANCELLED
