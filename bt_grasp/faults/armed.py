"""One arming of a fault: what armed it, and whether it has acted yet (the firing is recorded once)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from bt_grasp.faults.plan import Fault


@dataclass
class ArmedFault:
    """A fault armed by its trigger. ``fire`` records the first effect; ``finish`` ends it."""

    fault: Fault
    tick: int  # the tick during which (or after which) it was armed
    leaf: str | None  # the leaf whose entry armed it (None for a tick trigger)
    node: Any  # that leaf node (None for a tick trigger)
    on_fire: Callable[[ArmedFault, dict[str, Any]], None]
    fired: bool = False
    done: bool = False
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def params(self) -> Any:
        return self.fault.params

    def fire(self, **details: Any) -> None:
        """The fault acted on the cell for the first time in this arming: record it (once)."""
        if not self.fired:
            self.fired = True
            self.details = details
            self.on_fire(self, details)

    def finish(self) -> None:
        self.done = True
