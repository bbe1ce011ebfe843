"""BT.CPP 4.10 actions: AlwaysSuccess, AlwaysFailure, SetBlackboard, UnsetBlackboard, WasEntryUpdated, Sleep,
Script. Sleep reads the injected simulated clock."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from bt_grasp.tree.builtins.manifest import IN, INOUT, action
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import PortValueError, ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.leaf import Leaf
from bt_grasp.tree.ports import EntryWatch, convert_text
from bt_grasp.tree.registry import PortDirection, PortSpec
from bt_grasp.tree.scripting import Program, parse_script


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


class ScriptLeaf(Leaf):
    """A leaf running the script of its ``code`` port (parsed at load time when it is a literal)."""

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


class Script(ScriptLeaf):
    """Runs ``code``; always SUCCESS."""

    def update(self) -> Status:
        self.program().run(self.blackboard, self._bt_enums)
        return Status.SUCCESS


class UnsetBlackboard(Leaf):
    """Removes the entry ``key`` from the blackboard (a missing entry is not an error); SUCCESS."""

    def update(self) -> Status:
        self.blackboard.unset(str(self.ports.get("key")))
        return Status.SUCCESS


class WasEntryUpdated(Leaf):
    """SUCCESS when the entry was written since this node last looked (or ever, the first time), FAILURE
    otherwise or when it does not exist."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.watch = EntryWatch(ctx.attributes.get("entry", ""))

    def update(self) -> Status:
        return Status.SUCCESS if self.watch.written_since(self.blackboard) else Status.FAILURE


CODE_PORT = PortSpec("code", IN, str, description="the script to run")

SPECS = (
    action(AlwaysSuccess, "Returns SUCCESS."),
    action(AlwaysFailure, "Returns FAILURE."),
    action(
        SetBlackboard,
        "Writes a value into a blackboard entry.",
        (
            PortSpec("value", IN, object, description="the value, or {entry} to copy"),
            PortSpec("output_key", INOUT, str, description="the entry to write"),
        ),
    ),
    action(
        Sleep,
        "RUNNING until msec of simulated time passed.",
        (PortSpec("msec", IN, int, description="duration in milliseconds of simulated time"),),
    ),
    action(Script, "Runs a script; SUCCESS.", (CODE_PORT,)),
    action(
        UnsetBlackboard,
        "Removes a blackboard entry.",
        (PortSpec("key", IN, str, description="the entry to remove"),),
    ),
    action(
        WasEntryUpdated,
        "SUCCESS when the entry was written since this node last looked.",
        (PortSpec("entry", IN, object, description="the blackboard entry to watch ({key} or key)"),),
    ),
)
