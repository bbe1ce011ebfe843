"""BT.CPP 4.10 actions: AlwaysSuccess, AlwaysFailure, SetBlackboard, UnsetBlackboard, WasEntryUpdated, Sleep,
Script. Sleep reads the injected simulated clock.

They are written as a plugin's leaves are (``docs/own-leaves.md``): declared with ``@action``, registered by
:func:`register`."""

from __future__ import annotations

from bt_grasp.tree.exceptions import PortValueError, ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.node_api import Leaf, NodeContext, NodeRegistry, Status, action, inout_port, input_port
from bt_grasp.tree.ports import EntryWatch, convert_text
from bt_grasp.tree.registry import PortSpec
from bt_grasp.tree.scripting import Program, parse_script


@action(description="Returns SUCCESS.")
class AlwaysSuccess(Leaf):
    def update(self) -> Status:
        return Status.SUCCESS


@action(description="Returns FAILURE.")
class AlwaysFailure(Leaf):
    def update(self) -> Status:
        return Status.FAILURE


@action(
    ports=[input_port("msec", int, description="duration in milliseconds of simulated time", required=True)],
    description="RUNNING until msec of simulated time passed.",
)
class Sleep(Leaf):
    """RUNNING until ``msec`` of simulated time passed since the first tick, then SUCCESS."""

    def initialise(self) -> None:
        self.until_ns = self.clock.now_ns() + self.ports.require("msec", int) * 1_000_000
        self.first = True

    def update(self) -> Status:
        first, self.first = self.first, False
        if self.clock.now_ns() >= self.until_ns and not (first and self.ports.require("msec", int) > 0):
            return Status.SUCCESS
        return Status.RUNNING


@action(
    ports=[
        input_port("value", object, description="the value, or {entry} to copy", required=True),
        inout_port("output_key", str, "the entry to write", required=True),
    ],
    description="Writes a value into a blackboard entry.",
)
class SetBlackboard(Leaf):
    """Writes ``value`` (a literal, or a copy of ``{entry}``) into the entry named by ``output_key``."""

    def update(self) -> Status:
        key = self.ports.key("output_key") or self.ports.require("output_key", str)
        value = self.ports.require("value")
        entry = self.blackboard.entry(key)
        current = entry.value if entry is not None else None
        if isinstance(value, str) and isinstance(current, bool | int | float) and self.ports.key("value") is None:
            try:
                value = convert_text(value, input_port("value", type(current)))
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
            self._program = parse_script(ctx.ports.require("code", str))

    def program(self) -> Program:
        if self._program is not None:
            return self._program
        try:
            return parse_script(self.ports.require("code", str))
        except ScriptSyntaxError as exc:
            raise TreeRuntimeError(f"{self.bt_path}: {exc}") from None


def code_port() -> PortSpec:
    """The ``code`` port of Script and ScriptCondition."""
    return input_port("code", str, description="the script to run", required=True)


@action(ports=[code_port()], description="Runs a script; SUCCESS.")
class Script(ScriptLeaf):
    """Runs ``code``; always SUCCESS."""

    def update(self) -> Status:
        self.program().run(self.blackboard, self.enums)
        return Status.SUCCESS


@action(
    ports=[input_port("key", str, description="the entry to remove", required=True)],
    description="Removes a blackboard entry.",
)
class UnsetBlackboard(Leaf):
    """Removes the entry ``key`` from the blackboard (a missing entry is not an error); SUCCESS."""

    def update(self) -> Status:
        self.blackboard.unset(self.ports.require("key", str))
        return Status.SUCCESS


@action(
    ports=[input_port("entry", object, description="the blackboard entry to watch ({key} or key)", required=True)],
    description="SUCCESS when the entry was written since this node last looked.",
)
class WasEntryUpdated(Leaf):
    """SUCCESS when the entry was written since this node last looked (or ever, the first time), FAILURE
    otherwise or when it does not exist."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.watch = EntryWatch(ctx.attributes.get("entry", ""))

    def update(self) -> Status:
        return Status.SUCCESS if self.watch.written_since(self.blackboard) else Status.FAILURE


NODES: tuple[type[Leaf], ...] = (AlwaysSuccess, AlwaysFailure, SetBlackboard, Sleep, Script, UnsetBlackboard,
                                 WasEntryUpdated)


def register(registry: NodeRegistry) -> None:
    """BT.CPP's built-in actions, registered as a plugin registers its nodes."""
    for node in NODES:
        registry.register(node)
