"""The public API for writing one's own nodes: leaves, controls, decorators and failure reasons.

Everything a plugin author needs is importable from here (see docs/own-leaves.md for a complete example)::

    from bt_grasp.nodes import RobotLeaf, Reason, Status, action, input_port, output_port

    BARCODE_UNREADABLE = Reason("BARCODE_UNREADABLE", "The label could not be read.")

    @action(ports=[input_port("timeout_s", float, 2.0, "give up after this much simulated time")],
            needs_robot=True, reasons=[BARCODE_UNREADABLE])
    class ReadBarcode(RobotLeaf):
        '''Reads the barcode of the object in front of the camera.'''

        def initialise(self) -> None:               # one attempt starts
            self.deadline = Deadline.after(self.clock, self.input_float("timeout_s"))

        def update(self) -> Status:                 # once per tick (one control period), never blocks
            frame = self.cell.camera.capture()
            ...
            if self.deadline.passed():
                return self.failed(BARCODE_UNREADABLE, "no label found before the timeout")
            return Status.RUNNING

    def register(registry: NodeRegistry) -> None:  # BT.CPP's BT_REGISTER_NODES
        registry.register_reason(BARCODE_UNREADABLE)
        registry.register(ReadBarcode.bt_spec)

The lifecycle (py_trees' with BT.CPP's halting): ``__init__`` stores configuration only (the tree can be
validated and drawn with no simulator); ``setup(cell=...)`` receives the run's services once before the first
tick (:class:`RobotLeaf` keeps them as ``self.cell``: robot, camera, clock, planner, kinematics, calibration,
media); ``initialise()`` starts an attempt; ``update()`` runs once per tick and returns RUNNING, SUCCESS or
FAILURE; ``terminate(new_status)`` follows a finished update, or comes with ``Status.INVALID`` when a parent
halts the RUNNING leaf. Time is simulated: read ``self.clock`` (or use :class:`Deadline`), never the wall clock.

Controls and decorators subclass :class:`Control` / :class:`Decorator` and implement ``bt_tick() -> BtStatus``
with BT.CPP's rules (tick children with ``tick_child``/``_tick_child``, halt them with ``halt_child``/
``reset_children``, return RUNNING/SUCCESS/FAILURE/SKIPPED).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, TypeVar

from py_trees.common import Status

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.clock import Clock
from bt_grasp.tree.builtins.controls import Control
from bt_grasp.tree.builtins.decorators import Decorator
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.leaf import Leaf
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.plugins import ENTRY_POINT_GROUP, PluginError
from bt_grasp.tree.reasons import FailureReason, Reason, ReasonLike
from bt_grasp.tree.registry import (
    NO_DEFAULT,
    NodeKind,
    NodeRegistry,
    NodeSpec,
    PortDirection,
    PortSpec,
    leaf,
)

__all__ = [
    "ENTRY_POINT_GROUP",
    "NO_DEFAULT",
    "BtNode",
    "BtStatus",
    "Clock",
    "Control",
    "Deadline",
    "DeclarationError",
    "Decorator",
    "FailureReason",
    "Leaf",
    "NodeContext",
    "NodeKind",
    "NodeRegistry",
    "NodeSpec",
    "PluginError",
    "PortDirection",
    "PortSpec",
    "Reason",
    "RobotLeaf",
    "Status",
    "action",
    "condition",
    "control",
    "decorator",
    "inout_port",
    "input_port",
    "output_port",
]

T = TypeVar("T")


def input_port(name: str, type: type = str, default: Any = NO_DEFAULT, description: str = "") -> PortSpec:
    """BT.CPP ``InputPort<T>(name, default, description)``; no default makes the port required."""
    return PortSpec(name, PortDirection.INPUT, type, default, description)


def output_port(name: str, type: type = object, description: str = "") -> PortSpec:
    """BT.CPP ``OutputPort<T>``: the tree gives a blackboard key (``grasp="{grasp}"``)."""
    return PortSpec(name, PortDirection.OUTPUT, type, NO_DEFAULT, description)


def inout_port(name: str, type: type = object, description: str = "") -> PortSpec:
    return PortSpec(name, PortDirection.INOUT, type, NO_DEFAULT, description)


def action(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), needs_robot: bool = False,
    description: str | None = None, reasons: Iterable[ReasonLike] = (),
) -> Callable[[T], T]:
    """Class decorator for a :class:`Leaf` that acts; the spec is stored as ``cls.bt_spec`` (register it in
    ``register(registry)``). ``needs_robot``: it uses the cell (robot, camera, planner); it then updates at most
    once per control period, and ``tree run --dry`` replaces it by a stand-in. ``reasons``: the failure reasons it
    may report (register each with ``registry.register_reason`` first); the stand-in fails with them."""
    return leaf(None, name=name, kind=NodeKind.ACTION, ports=ports, needs_robot=needs_robot, description=description,
                reasons=reasons)


def condition(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), needs_robot: bool = False,
    description: str | None = None, reasons: Iterable[ReasonLike] = (),
) -> Callable[[T], T]:
    """Class decorator for a :class:`Leaf` that checks something (SUCCESS or FAILURE, never RUNNING)."""
    return leaf(
        None, name=name, kind=NodeKind.CONDITION, ports=ports, needs_robot=needs_robot, description=description,
        reasons=reasons,
    )


def _branch(kind: NodeKind, name: str | None, ports: Iterable[PortSpec], description: str | None,
            children: tuple[int, int | None] | None) -> Callable[[T], T]:
    def decorate(cls: T) -> T:
        doc = (getattr(cls, "__doc__", None) or "").strip().splitlines()
        cls.bt_spec = NodeSpec(  # type: ignore[attr-defined]
            name=name or cls.__name__,  # type: ignore[attr-defined]
            kind=kind,
            ports=tuple(ports),
            factory=cls,  # type: ignore[arg-type]
            description=description if description is not None else (doc[0] if doc else ""),
            children=children,
        )
        return cls

    return decorate


def control(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), description: str | None = None,
    children: tuple[int, int | None] = (1, None),
) -> Callable[[T], T]:
    """Class decorator for a :class:`Control` subclass (``children``: min and max, None for unbounded)."""
    return _branch(NodeKind.CONTROL, name, ports, description, children)


def decorator(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), description: str | None = None,
) -> Callable[[T], T]:
    """Class decorator for a :class:`Decorator` subclass (exactly one child)."""
    return _branch(NodeKind.DECORATOR, name, ports, description, None)


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
