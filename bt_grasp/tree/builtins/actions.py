"""Built-in leaves: AlwaysSuccess, AlwaysFailure, SetBlackboard, Sleep, Script, ScriptCondition (BT.CPP's),
FailureIs (bt_grasp's) and TestNode (the stand-in ``--substitute`` builds)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from py_trees.common import Status

from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import PortValueError, ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.leaf import FAILED_LEAF_KEY, FAILURE_REASON_KEY, Leaf
from bt_grasp.tree.ports import convert_text
from bt_grasp.tree.registry import PortDirection, PortSpec
from bt_grasp.tree.script import parse_script
from bt_grasp.tree.script_ast import Program


class AlwaysSuccess(Leaf):
    def update(self) -> Status:
        return Status.SUCCESS


class AlwaysFailure(Leaf):
    def update(self) -> Status:
        return Status.FAILURE


class Sleep(Leaf):
    """RUNNING until ``msec`` of simulated time passed since the first tick, then SUCCESS."""

    def initialise(self) -> None:
        self.until_ns = self.clock.now_ns() + int(self.ports.get("msec")) * 1_000_000
        self.first = True

    def update(self) -> Status:
        first, self.first = self.first, False
        if self.clock.now_ns() >= self.until_ns and not (first and int(self.ports.get("msec")) > 0):
            return Status.SUCCESS
        return Status.RUNNING


class SetBlackboard(Leaf):
    """Writes ``value`` (a literal, or a copy of ``{entry}``) into the entry named by ``output_key``."""

    def update(self) -> Status:
        key = self.ports.key("output_key") or str(self.ports.get("output_key"))
        value: Any = self.ports.get("value")
        entry = self.blackboard.entry(key)
        current = entry.value if entry is not None else None
        if isinstance(value, str) and isinstance(current, bool | int | float) and self.ports.key("value") is None:
            spec = PortSpec("value", PortDirection.INPUT, type(current))
            try:
                value = convert_text(value, spec)
            except PortValueError as exc:
                raise TreeRuntimeError(f"{self.bt_path}: entry '{key}' holds {current!r}; {exc}") from None
        self.blackboard.set(key, value)
        return Status.SUCCESS


class _ScriptLeaf(Leaf):
    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self._program: Program | None = None
        if ctx.ports.key("code") is None:  # a literal script is parsed (and checked) at load time
            self._program = parse_script(str(ctx.ports.get("code")))

    def program(self) -> Program:
        if self._program is not None:
            return self._program
        try:
            return parse_script(str(self.ports.get("code")))
        except ScriptSyntaxError as exc:
            raise TreeRuntimeError(f"{self.bt_path}: {exc}") from None


class Script(_ScriptLeaf):
    """Runs ``code``; always SUCCESS."""

    def update(self) -> Status:
        self.program().run(self.blackboard, self._bt_enums)
        return Status.SUCCESS


class ScriptCondition(_ScriptLeaf):
    """SUCCESS when ``code`` evaluates to true, FAILURE otherwise."""

    def update(self) -> Status:
        return Status.SUCCESS if self.program().truth(self.blackboard, self._bt_enums) else Status.FAILURE


class FailureIs(Leaf):
    """SUCCESS when the last :meth:`Leaf.fail` reason (root blackboard ``failure_reason``) is ``reason``
    (and, when ``leaf`` is given, the failing leaf had that name)."""

    def update(self) -> Status:
        root = self.blackboard.root
        reason = root.get(FAILURE_REASON_KEY, None)
        wanted_leaf = str(self.ports.get("leaf"))
        if reason != self.ports.get("reason"):
            return Status.FAILURE
        if wanted_leaf and root.get(FAILED_LEAF_KEY, None) != wanted_leaf:
            return Status.FAILURE
        return Status.SUCCESS


@dataclass(frozen=True)
class TestBehaviour:
    """What a TestNode does: RUNNING for ``running_ticks`` ticks, then ``result``; a FAILURE with a
    ``reason`` is reported through :meth:`Leaf.fail` (so ``FailureIs`` sees it)."""

    __test__ = False  # not a pytest test class

    running_ticks: int = 0
    result: Status = Status.SUCCESS
    reason: str | None = None


class TestNode(Leaf):
    """A stand-in leaf built by substitution rules (``Approach=Running:3``)."""

    __test__ = False

    def __init__(self, ctx: NodeContext, behaviour: TestBehaviour) -> None:
        super().__init__(ctx)
        self.behaviour = behaviour
        self.ticks = 0

    def initialise(self) -> None:
        self.ticks = 0

    def update(self) -> Status:
        if self.ticks < self.behaviour.running_ticks:
            self.ticks += 1
            return Status.RUNNING
        if self.behaviour.result == Status.FAILURE and self.behaviour.reason:
            return self.fail(self.behaviour.reason, f"stand-in for {self.name} was told to fail")
        return self.behaviour.result
