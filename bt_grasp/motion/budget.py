"""Deterministic work budgets for searches, with a wall-clock safety net that is never the normal end.

A search ends when it has spent a fixed amount of *work* (here: state validity checks), so the same
request and seed explore exactly the same states on an idle laptop and on a loaded cluster node. A
wall-clock limit stays only as a safety net against a pathological request (a planner that stops checking
states, a checker that hangs); when it fires, the search fails with its own named status
(``PlanStatus.SAFETY_TIMEOUT``) and a warning is logged, so a run that depended on it is visible in the
log and never mistaken for an ordinary budget exhaustion.

Only the safety net reads the clock (``time.perf_counter``); no decision of a normal run depends on it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from ompl import base as ob

log = logging.getLogger(__name__)


@dataclass
class WorkBudget:
    """Counts validity checks against a fixed budget; ``ptc()`` gives OMPL a termination condition.

    ``limit`` checks may be spent in total (search and simplification share one budget object each).
    ``safety_deadline`` is a ``time.perf_counter()`` value: passing it also ends the search, and sets
    ``safety_hit``.
    """

    limit: int
    safety_deadline: float
    spent: int = 0
    safety_hit: bool = field(default=False)

    @classmethod
    def start(cls, limit: int, safety_limit_s: float) -> WorkBudget:
        return cls(int(limit), time.perf_counter() + float(safety_limit_s))

    @property
    def exhausted(self) -> bool:
        return self.spent >= self.limit

    def sub(self, limit: int) -> WorkBudget:
        """A fresh count of ``limit`` checks under the same safety deadline."""
        return WorkBudget(int(limit), self.safety_deadline)

    def wrap(self, valid: Callable[[np.ndarray], bool]) -> Callable[[object], bool]:
        """An OMPL state validity callable that counts every check it makes."""

        def checked(state: object) -> bool:
            self.spent += 1
            return valid(np.array([state[i] for i in range(6)]))  # type: ignore[index]

        return checked

    def should_stop(self) -> bool:
        if self.spent >= self.limit:
            return True
        if time.perf_counter() > self.safety_deadline:
            if not self.safety_hit:
                log.warning("wall-clock safety net hit after %d of %d checks: the search is stopped",
                            self.spent, self.limit)
            self.safety_hit = True
            return True
        return False

    def ptc(self) -> ob.PlannerTerminationCondition:
        return ob.PlannerTerminationCondition(self.should_stop)
