"""Simulated time. Timeouts, delays, log stamps and back-off read an injected clock, never the wall clock."""

from __future__ import annotations

from typing import Protocol


class Clock(Protocol):
    """Anything that tells the current simulated time."""

    def now_ns(self) -> int:
        """Simulated time since the start of the run, in nanoseconds."""
        ...


class ManualClock:
    """A clock advanced by its owner: the world advances it as physics steps, tests advance it by hand."""

    def __init__(self, start_ns: int = 0) -> None:
        self._now_ns = int(start_ns)

    def now_ns(self) -> int:
        return self._now_ns

    def now_s(self) -> float:
        return self._now_ns * 1e-9

    def advance_ns(self, delta_ns: int) -> None:
        if delta_ns < 0:
            raise ValueError("a clock cannot go backwards")
        self._now_ns += int(delta_ns)

    def restart(self) -> None:
        """Back to 0 for a new episode in a reused world (the only way this clock goes back)."""
        self._now_ns = 0

    def advance_s(self, delta_s: float) -> None:
        self.advance_ns(round(delta_s * 1e9))
