"""The differential driver's test leaves (tools/btcpp_diff/driver.cpp), written as bt_grasp leaves.

They are registered for tests only (:func:`conformance_registry`), never in the product's registry. Each one
counts its ticks, starts and halts in a shared :class:`Traces` so a run can be compared with BT.CPP's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from bt_grasp.nodes import (
    Leaf,
    NodeContext,
    NodeRegistry,
    Status,
    action,
    condition,
    inout_port,
    input_port,
    output_port,
)
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.plugins import load_plugins

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


@action(ports=[input_port("result", str, "SUCCESS"), input_port("running", int, 0)])
class TestAction(_Traced):
    """RUNNING for ``running`` ticks after it starts, then ``result``."""

    __test__ = False

    def initialise(self) -> None:
        self.done = 0
        self.traces[self.name].starts += 1

    def update(self) -> Status:
        self.count_tick()
        if self.done < self.ports.require("running", int):
            self.done += 1
            return Status.RUNNING
        return {"SUCCESS": Status.SUCCESS, "FAILURE": Status.FAILURE}[self.ports.require("result", str)]

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:
            self.traces[self.name].halts += 1


@condition(ports=[input_port("value", bool)])
class TestCondition(_Traced):
    """SUCCESS when the input port ``value`` reads true."""

    __test__ = False

    def update(self) -> Status:
        self.count_tick()
        return Status.SUCCESS if self.ports.require("value", bool) else Status.FAILURE


@action(ports=[inout_port("value", int), input_port("step", int, 1)])
class Counter(_Traced):
    """Reads the integer ``value`` (0 when empty), writes value + ``step``."""

    def update(self) -> Status:
        self.count_tick()
        try:  # BT.CPP's getInput returns an error (not an exception) for an empty or unconvertible entry
            current = self.ports.get("value", int) or 0
        except TreeRuntimeError:
            current = 0
        self.ports.set("value", current + self.ports.require("step", int))
        return Status.SUCCESS


@action(ports=[input_port("value", float), output_port("out", float)])
class WriteReal(_Traced):
    def update(self) -> Status:
        self.count_tick()
        self.ports.set("out", self.ports.require("value", float))
        return Status.SUCCESS


@action(ports=[input_port("text", str), output_port("out", str)])
class EchoText(_Traced):
    def update(self) -> Status:
        self.count_tick()
        self.ports.set("out", self.ports.require("text", str))
        return Status.SUCCESS


STANDINS = Path(__file__).parent / "standins.py"


def conformance_registry(traces: Traces) -> NodeRegistry:
    """The built-in registry plus the driver's test leaves and enums, and the stand-ins of other projects' nodes
    (``standins.py``, loaded as a user's ``--leaves`` plugin file is)."""
    registry = builtin_registry()
    load_plugins(registry, [str(STANDINS)], installed=False)
    for node in (TestAction, TestCondition, Counter, WriteReal, EchoText):
        registry.register(node, args=(traces,))  # BT.CPP's registerNodeType<T>(name, args...)
    registry.register_enums(ENUMS)
    return registry
