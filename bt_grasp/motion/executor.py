"""Executes a sampled joint trajectory on a :class:`~bt_grasp.interfaces.Robot`, one control period per call.

The executor never advances time: a behaviour-tree leaf calls :meth:`TrajectoryExecutor.update` once per tick
(the caller steps the world between ticks) and returns RUNNING while the executor does. Each update reads the
injected clock, commands the trajectory's position and velocity at that time, and watches the tracking error:
above ``max_tracking_error_rad`` for longer than ``tracking_error_grace_s`` (a stall or a collision) it fails.
After the last sample it holds the goal until the arm has settled (within ``settle_tolerance_rad``, slower than
``settle_velocity_rad_s``; or at rest, its measured joints within ``rest_still_rad`` of where they were for
``rest_periods`` updates, within ``rest_tolerance_rad``) or ``settle_timeout_s`` of simulated time passed.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.clock import Clock
from bt_grasp.interfaces import Robot
from bt_grasp.motion.trajectory import Trajectory

log = logging.getLogger(__name__)


class ExecStatus(enum.Enum):
    IDLE = "idle"  # not started
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"


class ExecFailure(enum.Enum):
    TRACKING_ERROR = "tracking_error"  # the arm lagged the trajectory too far for too long
    SETTLE_TIMEOUT = "settle_timeout"  # the arm did not come to rest on the goal in time


@dataclass(frozen=True)
class ExecutorOptions:
    max_tracking_error_rad: float = 0.1  # on any joint
    tracking_error_grace_s: float = 0.05  # how long the error may stay above the bound
    settle_tolerance_rad: float = 1e-3  # joint error that counts as arrived
    settle_velocity_rad_s: float = 0.01  # joint speed that counts as at rest
    settle_timeout_s: float = 2.0  # after the last sample
    # an arm that has come to rest (its measured joints within rest_still_rad of where they were rest_periods
    # updates before, all along: the physics engine may stop it or keep it jittering in place, reported
    # velocities notwithstanding) within this of the goal has arrived as near as it will: waiting changes nothing
    rest_tolerance_rad: float = 3e-3
    rest_still_rad: float = 5e-4
    rest_periods: int = 25


class TrajectoryExecutor:
    """Streams a :class:`Trajectory` to a robot; ``update()`` once per control period."""

    def __init__(self, robot: Robot, trajectory: Trajectory, clock: Clock,
                 options: ExecutorOptions | None = None) -> None:
        self.robot = robot
        self.trajectory = trajectory
        self.clock = clock
        self.options = options or ExecutorOptions()
        self.status = ExecStatus.IDLE
        self.reason: ExecFailure | None = None
        self.max_tracking_error_rad = 0.0
        self._start_ns: int | None = None
        self._error_since_ns: int | None = None
        self._last_q: NDArray[np.float64] | None = None  # after the last sample: to tell when the arm is at rest
        self._still_periods = 0
        #: the joints measured by the last update (None before the first): a caller logging the executed
        #: motion reads them here instead of asking the robot again
        self.q_measured: NDArray[np.float64] | None = None

    @property
    def elapsed_s(self) -> float:
        return 0.0 if self._start_ns is None else (self.clock.now_ns() - self._start_ns) * 1e-9

    def start(self) -> None:
        """Start now (the clock's current time is trajectory time 0) and command the first sample."""
        self._start_ns = self.clock.now_ns()
        self._error_since_ns = None
        self._last_q, self._still_periods = None, 0
        self.status = ExecStatus.RUNNING
        self.reason = None
        q, qd, _ = self.trajectory.sample(0.0)
        self.robot.set_joint_targets(q, qd)
        log.debug("trajectory started: %.3f s, %d samples", self.trajectory.duration_s, len(self.trajectory.q))

    def update(self) -> ExecStatus:
        """Check the last period's tracking, then command the sample for the current time."""
        self.q_measured = None
        if self.status is not ExecStatus.RUNNING:
            return self.status
        assert self._start_ns is not None
        now_ns = self.clock.now_ns()
        t = (now_ns - self._start_ns) * 1e-9
        opts = self.options
        q_desired, qd_desired, _ = self.trajectory.sample(t)
        q_measured = self.q_measured = self.robot.joint_positions()
        error = float(np.max(np.abs(q_measured - q_desired)))
        self.max_tracking_error_rad = max(self.max_tracking_error_rad, error)
        if error > opts.max_tracking_error_rad:
            if self._error_since_ns is None:
                self._error_since_ns = now_ns
            elif (now_ns - self._error_since_ns) * 1e-9 > opts.tracking_error_grace_s:
                return self._fail(ExecFailure.TRACKING_ERROR, q_measured,
                                  f"tracking error {error:.3f} rad for more than {opts.tracking_error_grace_s} s")
        else:
            self._error_since_ns = None
        if t < self.trajectory.duration_s:
            self.robot.set_joint_targets(q_desired, qd_desired)  # the sample for now, taken above
            return self.status
        goal = self.trajectory.q[-1]
        self.robot.set_joint_targets(goal, np.zeros(6))
        speed = float(np.max(np.abs(self.robot.joint_velocities())))
        still = self._last_q is not None and float(np.max(np.abs(q_measured - self._last_q))) < opts.rest_still_rad
        self._still_periods = self._still_periods + 1 if still else 0
        if not still:  # a new window starts here: the arm is compared with where it was at the window's start
            self._last_q = q_measured
        at_rest = self._still_periods >= opts.rest_periods and error < opts.rest_tolerance_rad
        if (error < opts.settle_tolerance_rad and speed < opts.settle_velocity_rad_s) or at_rest:
            self.status = ExecStatus.SUCCEEDED
            log.debug("trajectory done after %.3f s (max tracking error %.4f rad, final %.4f rad%s)", t,
                      self.max_tracking_error_rad, error, ", at rest" if at_rest else "")
        elif t > self.trajectory.duration_s + opts.settle_timeout_s:
            return self._fail(ExecFailure.SETTLE_TIMEOUT, q_measured,
                              f"not settled {opts.settle_timeout_s} s after the end (error {error:.4f} rad)")
        return self.status

    def cancel(self) -> None:
        """Stop: hold the current measured position (a halted leaf calls this)."""
        if self.status is ExecStatus.RUNNING:
            self._hold(self.robot.joint_positions())
            self.status = ExecStatus.CANCELLED
            log.debug("trajectory cancelled at %.3f s", self.elapsed_s)

    def _hold(self, q: NDArray[np.float64]) -> None:
        self.robot.set_joint_targets(np.asarray(q, dtype=float), np.zeros(6))

    def _fail(self, reason: ExecFailure, q_measured: NDArray[np.float64], message: str) -> ExecStatus:
        self._hold(q_measured)
        self.status = ExecStatus.FAILED
        self.reason = reason
        log.warning("trajectory failed: %s", message)
        return self.status
