"""The differential driver's test leaves (tools/btcpp_diff/driver.cpp), written as bt_grasp leaves.

They are registered for tests only (:func:`conformance_registry`), never in the product's registry. Each one
counts its ticks, starts and halts in a shared :class:`Traces` so a run can be compared with BT.CPP's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from py_trees.common import Status

from bt_grasp.tree import Leaf, NodeContext, NodeKind, NodeRegistry, NodeSpec, PortDirection, PortSpec
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.plugins import load_plugins

IN, OUT, INOUT = PortDirection.INPUT, PortDirection.OUTPUT, PortDirection.INOUT
ENUMS = {"RED": 1, "GREEN": 2, "BLUE": 3}


@dataclass
class Trace:
    ticks: int = 0
    starts: int = 0
    halts: int = 0


@dataclass
class Traces:
    by_name: dict[str, Trace] = field(default_factory=dict)

    def __getitem__(self, name: str) -> Trace:
        return self.by_name.setdefault(name, Trace())

    def as_json(self) -> dict[str, dict[str, int]]:
        return {k: {"ticks": v.ticks, "starts": v.starts, "halts": v.halts} for k, v in sorted(self.by_name.items())}


class _Traced(Leaf):
    def __init__(self, ctx: NodeContext, traces: Traces) -> None:
        super().__init__(ctx)
        self.traces = traces

    def count_tick(self) -> Trace:
        trace = self.traces[self.name]
        trace.ticks += 1
        return trace


class TestAction(_Traced):
    """RUNNING for ``running`` ticks after it starts, then ``result``."""

    __test__ = False

    def initialise(self) -> None:
        self.done = 0
        self.traces[self.name].starts += 1

    def update(self) -> Status:
        self.count_tick()
        if self.done < int(self.ports.get("running")):
            self.done += 1
            return Status.RUNNING
        return {"SUCCESS": Status.SUCCESS, "FAILURE": Status.FAILURE}[str(self.ports.get("result"))]

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID:
            self.traces[self.name].halts += 1


class TestCondition(_Traced):
    """SUCCESS when the input port ``value`` reads true."""

    __test__ = False

    def update(self) -> Status:
        self.count_tick()
        return Status.SUCCESS if self.ports.get("value") else Status.FAILURE


class Counter(_Traced):
    """Reads the integer ``value`` (0 when empty), writes value + ``step``."""

    def update(self) -> Status:
        self.count_tick()
        try:  # BT.CPP's getInput returns an error (not an exception) for an empty or unconvertible entry
            current = self.ports.get("value")
        except TreeRuntimeError:
            current = 0
        self.ports.set("value", current + int(self.ports.get("step")))
        return Status.SUCCESS


class WriteReal(_Traced):
    def update(self) -> Status:
        self.count_tick()
        self.ports.set("out", float(self.ports.get("value")))
        return Status.SUCCESS


class EchoText(_Traced):
    def update(self) -> Status:
        self.count_tick()
        self.ports.set("out", str(self.ports.get("text")))
        return Status.SUCCESS


STANDINS = Path(__file__).parent / "standins.py"


def conformance_registry(traces: Traces) -> NodeRegistry:
    """The built-in registry plus the driver's test leaves and enums, and the stand-ins of other projects' nodes
    (``standins.py``, loaded as a user's ``--leaves`` plugin file is)."""
    registry = builtin_registry()
    load_plugins(registry, [str(STANDINS)], installed=False)

    def spec(cls: type[_Traced], kind: NodeKind, ports: tuple[PortSpec, ...]) -> NodeSpec:
        return NodeSpec(cls.__name__, kind, ports, lambda ctx: cls(ctx, traces), cls.__doc__ or "")

    registry.register(
        spec(
            TestAction,
            NodeKind.ACTION,
            (PortSpec("result", IN, str, "SUCCESS"), PortSpec("running", IN, int, 0)),
        )
    )
    registry.register(spec(TestCondition, NodeKind.CONDITION, (PortSpec("value", IN, bool),)))
    registry.register(spec(Counter, NodeKind.ACTION, (PortSpec("value", INOUT, int), PortSpec("step", IN, int, 1))))
    registry.register(spec(WriteReal, NodeKind.ACTION, (PortSpec("value", IN, float), PortSpec("out", OUT, float))))
    registry.register(spec(EchoText, NodeKind.ACTION, (PortSpec("text", IN, str), PortSpec("out", OUT, str))))
    registry.register_enums(ENUMS)
    return registry
