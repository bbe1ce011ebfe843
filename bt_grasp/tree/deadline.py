"""A point in simulated time, for leaves that give up after a while."""

from __future__ import annotations

from dataclasses import dataclass

from bt_grasp.clock import Clock


@dataclass(frozen=True)
class Deadline:
    """A point in simulated time: ``Deadline.after(self.clock, 2.0).passed()`` (never the wall clock)."""

    clock: Clock
    end_ns: int

    @classmethod
    def after(cls, clock: Clock, seconds: float) -> Deadline:
        return cls(clock, clock.now_ns() + round(seconds * 1e9))

    def passed(self) -> bool:
        return self.clock.now_ns() >= self.end_ns

    def remaining_s(self) -> float:
        return max(0, self.end_ns - self.clock.now_ns()) * 1e-9
