"""Time on a real cell is wall time: the clock and the stepper of hardware runs (and of runs against the twin).

A simulated run's time is the world's (``bt_grasp.sim``): it passes only when physics steps. A real cell's passes on
its own, so its run reads the wall clock here and nowhere else: :class:`WallClock` is the run's
:class:`bt_grasp.clock.Clock` (timeouts, rates and log stamps keep their meaning: a second is a second), and
:class:`CellStepper` is its :class:`bt_grasp.interfaces.Stepper`: ``step()`` waits for the next control period's
deadline, then polls the cell (``poll``: the controller's state, the watchdog's kick, the gripper), which raises a
:class:`~bt_grasp.hardware.cell_faults.CellFault` when the cell ended the run.

:class:`MotionClock` is trajectory time: each period it advances by the period's wall time, at most one period (a
late tick slows the motion instead of making the next target jump), times the controller's speed scaling (the speed
slider), so the executor's tracking and settling checks follow the arm the slider slows.
"""

from __future__ import annotations

import time
from collections.abc import Callable


class WallClock:
    """Nanoseconds of wall time (monotonic) since the clock was made (the run's start)."""

    def __init__(self) -> None:
        self._start_ns = time.monotonic_ns()

    def now_ns(self) -> int:
        return time.monotonic_ns() - self._start_ns

    @property
    def start_ns(self) -> int:
        """The monotonic clock's reading at the start."""
        return self._start_ns


class MotionClock:
    """Trajectory time, advanced by :class:`CellStepper` (see the module docstring)."""

    def __init__(self) -> None:
        self._now_ns = 0

    def now_ns(self) -> int:
        return self._now_ns

    def advance_ns(self, delta_ns: int) -> None:
        self._now_ns += max(0, int(delta_ns))


#: ``poll(stalled_s)`` -> the speed scaling now (0..1); ``stalled_s``: wall time since the last poll
Poll = Callable[[float], float]


class CellStepper:
    """Implements :class:`bt_grasp.interfaces.Stepper` on the wall clock (see the module docstring)."""

    def __init__(self, clock: WallClock, period_s: float, poll: Poll, motion_clock: MotionClock | None = None) -> None:
        self.clock = clock
        self._period_s = float(period_s)
        self._period_ns = round(period_s * 1e9)
        self._poll = poll
        self.motion_clock = motion_clock or MotionClock()
        self._deadline = time.monotonic()
        self._last_poll = time.monotonic()
        self._last_ns = clock.now_ns()
        #: periods whose deadline had passed by more than a period before the tick loop got to it
        self.overruns = 0
        self.steps = 0

    @property
    def dt_s(self) -> float:
        return self._period_s

    def now_ns(self) -> int:
        return self.clock.now_ns()

    def restart(self) -> None:
        """The first period starts now (before the first tick)."""
        self._deadline = self._last_poll = time.monotonic()
        self._last_ns = self.clock.now_ns()

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            self._deadline += self._period_s
            now = time.monotonic()
            if now < self._deadline:
                time.sleep(self._deadline - now)
            elif now - self._deadline > self._period_s:
                self.overruns += 1
                self._deadline = now  # a late tick restarts the schedule: no burst of catch-up periods
            self.poll()
            self.steps += 1

    def poll(self) -> None:
        """Poll the cell now (also before the first tick): may raise a CellFault."""
        now = time.monotonic()
        scaling = self._poll(now - self._last_poll)
        self._last_poll = time.monotonic()
        now_ns = self.clock.now_ns()
        elapsed = min(now_ns - self._last_ns, self._period_ns)
        self._last_ns = now_ns
        self.motion_clock.advance_ns(round(elapsed * min(max(scaling, 0.0), 1.0)))
