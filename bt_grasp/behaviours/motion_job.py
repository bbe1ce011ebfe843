"""A motion made of segments (a planned path, a Cartesian line, ...), run one control period per tick.

Each segment's joint path is computed when the segment starts (from the arm's measured configuration),
time-parametrised with ruckig, and streamed by the trajectory executor while the leaf returns RUNNING.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.reasons import FailureReason

if TYPE_CHECKING:
    from bt_grasp.motion.executor import TrajectoryExecutor


@dataclass(frozen=True)
class PathFailure:
    reason: FailureReason
    sentence: str


#: computes a joint path (N, 6) from the measured configuration, or says why it cannot
PathFn = Callable[[NDArray[np.float64]], "NDArray[np.float64] | PathFailure"]


@dataclass(frozen=True)
class Segment:
    name: str
    path: PathFn


class MotionJob:
    """Runs segments in order. ``update()`` returns None while running, True when done, or a PathFailure."""

    def __init__(self, cell: Cell, segments: Sequence[Segment]) -> None:
        self.cell = cell
        self.segments = list(segments)
        self.index = 0
        self.executor: TrajectoryExecutor | None = None
        self.current = ""
        self._executed_t: list[float] = []
        self._executed_q: list[NDArray[np.float64]] = []

    def update(self) -> bool | PathFailure | None:
        # deferred: ruckig comes with it; a tree loads and validates without it
        from bt_grasp.motion.executor import ExecStatus

        if self.executor is None:
            if self.index >= len(self.segments):
                return True
            segment = self.segments[self.index]
            self.current = segment.name
            path = segment.path(self.cell.robot.joint_positions())
            if isinstance(path, PathFailure):
                return path
            started = self._start(segment.name, path)
            if isinstance(started, PathFailure):
                return started
            self.executor = started
            return None
        status = self.executor.update()
        self._executed_t.append(self.cell.clock.now_ns() * 1e-9)
        measured = getattr(self.executor, "q_measured", None)  # read by this update (nothing moved since)
        self._executed_q.append(measured if measured is not None else self.cell.robot.joint_positions())
        if status is ExecStatus.RUNNING:
            return None
        self.cell.media.trajectory(self.current, np.asarray(self._executed_t), np.asarray(self._executed_q), "executed")
        self._executed_t, self._executed_q = [], []
        if status is ExecStatus.SUCCEEDED:
            self.executor = None
            self.index += 1
            return True if self.index >= len(self.segments) else None
        reason = getattr(self.executor, "reason", None)
        error = getattr(self.executor, "max_tracking_error_rad", 0.0)
        message = f"{reason.value if reason else 'failed'} (max tracking error {error:.3f} rad)"
        self.executor = None
        return PathFailure(FailureReason.TRACKING_ERROR, f"{self.current}: {message}")

    def cancel(self) -> None:
        if self.executor is not None:
            self.executor.cancel()
            self.executor = None

    def _start(self, name: str, path: NDArray[np.float64]) -> TrajectoryExecutor | PathFailure:
        """The segment's trajectory, checked by the cell's guard (a real cell's) before anything of it is sent."""
        # deferred: ruckig comes with it; a tree loads and validates without it
        from bt_grasp.motion.executor import TrajectoryExecutor

        # deferred: ruckig comes with it; a tree loads and validates without it
        from bt_grasp.motion.trajectory import time_parametrize

        limits = self.cell.motion_limits
        rate_hz = self.cell.scene.physics.control_rate_hz
        trajectory = time_parametrize(np.asarray(path, dtype=float), limits, rate_hz=rate_hz, blend=True)
        if self.cell.guard is not None:
            checked = self.cell.guard.prepare(trajectory)
            if isinstance(checked, str):
                return PathFailure(FailureReason.SAFETY_LIMIT, f"{name}: refused before anything was sent: {checked}")
            trajectory = checked
        self.cell.media.trajectory(name, trajectory.times_s, trajectory.q, "planned")
        options = self.cell.executor_options
        clock = self.cell.motion_clock or self.cell.clock
        executor = TrajectoryExecutor(self.cell.robot, trajectory, clock, options)
        executor.start()
        return executor
