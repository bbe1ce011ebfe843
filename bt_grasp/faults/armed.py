"""One arming of a fault: what armed it, and whether it has acted yet (the firing is recorded once)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

from bt_grasp.faults.plan import Fault
from bt_grasp.files.config import StrictModel

if TYPE_CHECKING:
    from bt_grasp.tree.node import BtNode

_Params = TypeVar("_Params", bound=StrictModel)


@dataclass
class ArmedFault:
    """A fault armed by its trigger. ``fire`` records the first effect; ``finish`` ends it."""

    fault: Fault
    tick: int  # the tick during which (or after which) it was armed
    leaf: str | None  # the leaf whose entry armed it (None for a tick trigger)
    node: BtNode | None  # that leaf node (None for a tick trigger)
    on_fire: Callable[[ArmedFault, dict[str, object]], None]
    fired: bool = False
    done: bool = False
    details: dict[str, object] = field(default_factory=dict)

    @property
    def params(self) -> StrictModel:
        return self.fault.params

    def params_as(self, model: type[_Params]) -> _Params:
        """The fault's parameters as its kind's model (``model.PARAMS``); a TypeError for another kind's."""
        params = self.fault.params
        if not isinstance(params, model):
            raise TypeError(f"fault {self.fault.label}: {type(params).__name__}, not {model.__name__}")
        return params

    def fire(self, **details: object) -> None:
        """The fault acted on the cell for the first time in this arming: record it (once)."""
        if not self.fired:
            self.fired = True
            self.details = details
            self.on_fire(self, details)

    def finish(self) -> None:
        self.done = True
