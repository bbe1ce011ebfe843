"""BehaviorTree.CPP 4.10's substitution rules applied to a tree: its ``TestNode``, and which node a rule replaces.

:class:`TestNode` is BT.CPP's ``TestNode`` (``src/actions/test_node.cpp``), a ``StatefulActionNode``:

* ``onStart``: with no ``async_delay`` it completes at once; otherwise it is RUNNING, and its timer fires once
  ``async_delay`` ms passed -- here of **simulated** time, where BT.CPP's timer thread counts wall-clock time. The
  timer's firing is a wake-up (BT.CPP's ``emitWakeUpSignal``): the root executes again in that tick;
* ``onRunning``: RUNNING until the timer fired, then it completes (again at every tick while the completion
  says RUNNING); ``onHalted`` cancels the timer;
* completing: the status is ``return_status_script``'s value when there is one (evaluated with the statuses
  IDLE, RUNNING, SUCCESS, FAILURE, SKIPPED as scripting enums 0-4; a status name or number, IDLE refused), else
  ``return_status``; then ``success_script`` or ``failure_script``, then ``post_script``, with the tree's own
  enums only.

:class:`RuleSet` decides, for each node the builder makes, whether a rule replaces it, as BT.CPP's
``instantiateTreeNode`` does: a rule applies when its key equals the node's name or its type (registration ID),
or wildcard-matches its full path (``*``, ``?``); any node may be replaced (a control's children are then built
and left out of the tree, a SubTree's content is not built, as in BT.CPP). BT.CPP keeps its rules in an
unordered map, so when several match one node which one applies is unspecified; here the first in the file
applies, and :meth:`RuleSet.warnings` says so. A rule's target is a TestNodeConfig of the file, else a
registered node type (a leaf: the node becomes one of those, keeping its name and type and the ports that type
declares).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

from bt_grasp.errors import InputError, did_you_mean
from bt_grasp.tree.blackboard import EMPTY
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.kinds import NodeKind
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.outcomes import names_node
from bt_grasp.tree.registry import NodeRegistry, NodeSpec
from bt_grasp.tree.rules_file import RuleEntry, RuleFile, TestNodeConfig
from bt_grasp.tree.scripting import Program
from bt_grasp.tree.values import cast_to

#: BT.CPP's NodeStatus values, as ``return_status_script`` reads and returns them
STATUS_ENUMS: dict[str, int] = {"IDLE": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3, "SKIPPED": 4}
_BY_NUMBER = {number: BtStatus(name) for name, number in STATUS_ENUMS.items()}
_LEAF_KINDS = (NodeKind.ACTION, NodeKind.CONDITION)


class TestNode(Leaf):
    """BT.CPP's TestNode on simulated time (see the module)."""

    __test__ = False  # not a pytest test class

    def __init__(self, ctx: NodeContext, config: TestNodeConfig) -> None:
        super().__init__(ctx)
        self.config = config
        self._bt_once_per_period = False  # a BT.CPP node: every execution of the root ticks it
        self._starting = False
        self._completed = False
        self._fires_at_ns: int | None = None

    def initialise(self) -> None:
        self._starting = True

    def update(self) -> BtStatus:
        if self._starting:  # onStart
            self._starting = False
            if self.config.async_delay_ms <= 0:
                return self._complete()
            self._completed = False
            self._fires_at_ns = self.clock.now_ns() + self.config.async_delay_ms * 1_000_000
            return BtStatus.RUNNING
        if self._fires_at_ns is not None and self.clock.now_ns() >= self._fires_at_ns:  # the timer fired
            self._fires_at_ns = None
            self._completed = True
            self.emit_wake_up()
        if self._completed:  # onRunning
            return self._complete()
        return BtStatus.RUNNING

    def terminate(self, new_status: BtStatus) -> None:
        if new_status is BtStatus.IDLE:  # onHalted: the timer is cancelled
            self._fires_at_ns = None
            self._completed = False

    def _complete(self) -> BtStatus:
        """BT.CPP's ``onCompleted``."""
        config = self.config
        if config.return_status_script is not None:
            enums = {**self.enums, **STATUS_ENUMS}
            status = _status_of(config.return_status_script.run(self.blackboard, enums))
        else:
            status = config.return_status
        if status is BtStatus.IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: TestNode completion resolved to invalid status (integer value: "
                                   "0)")
        after: Program | None = None
        if status is BtStatus.SUCCESS:
            after = config.success_script
        elif status is BtStatus.FAILURE:
            after = config.failure_script
        for script in (after, config.post_script):
            if script is not None:
                script.run(self.blackboard, self.enums)
        return status


def _status_of(value: object) -> BtStatus:
    """BT.CPP's ``convertScriptResultToStatus``: a status name, or a number 1-4 (IDLE refused)."""
    source = "return_status_script"
    if value is None or value is EMPTY:
        raise TreeRuntimeError(f"{source} returned an empty value")
    if isinstance(value, str):
        if value not in STATUS_ENUMS:
            raise TreeRuntimeError(f"Cannot convert this to NodeStatus: {value}")
        status = BtStatus(value)
        number = STATUS_ENUMS[value]
    else:
        try:
            converted = cast_to(value, int)
        except TreeRuntimeError:
            converted = None
        if not isinstance(converted, int):
            raise TreeRuntimeError(f"{source} must evaluate to a NodeStatus-compatible value")
        number = converted
        status = _BY_NUMBER.get(number, BtStatus.IDLE)
    if status is BtStatus.IDLE:
        raise TreeRuntimeError(f"TestNode {source} resolved to invalid status (integer value: {number})")
    return status


@dataclass
class RuleSet:
    """A rule file bound to the registry its targets are looked up in; the builder's ``replacer``."""

    rules: RuleFile
    registry: NodeRegistry
    #: rule keys that replaced at least one node
    used: set[str] = field(default_factory=set)
    #: (keys of every rule matching, in file order) -> the paths of the nodes they matched
    overlaps: dict[tuple[str, ...], list[str]] = field(default_factory=dict)
    #: (rule key, what it replaced) for every control, decorator or SubTree a rule replaced
    non_leaves: list[tuple[str, str]] = field(default_factory=list)
    #: the rule keys that replaced a leaf
    leaf_keys: set[str] = field(default_factory=set)

    def __post_init__(self) -> None:
        for rule in self.rules.rules:
            if rule.config is None:
                self._target(rule)  # a bad target is refused before anything is built

    def _target(self, rule: RuleEntry) -> NodeSpec:
        where = f"{self.rules.where(rule)}"
        spec = self.registry.get(rule.target)
        if spec is None:
            known = [c.name for c in self.rules.configs] + list(self.registry.names())
            raise InputError(where, f"rule '{rule.key}': '{rule.target}' is neither a TestNodeConfig of this file nor "
                             f"a registered node type{did_you_mean(rule.target, known)}")
        if spec.kind not in _LEAF_KINDS:
            raise InputError(where, f"rule '{rule.key}': {rule.target} is {spec.kind.value}; only an action or a "
                             "condition (or a TestNodeConfig) can replace a node")
        if any(p.required for p in spec.ports):
            raise InputError(where, f"rule '{rule.key}': {rule.target} needs ports, so it cannot stand in for "
                             "another node")
        return spec

    def matching(self, type_id: str, name: str, path: str) -> list[RuleEntry]:
        return [r for r in self.rules.rules if names_node(r.key, type_id, name, path)]

    def replace(self, kind: NodeKind, type_id: str, name: str, path: str) -> NodeSpec | None:
        """The spec that replaces the node (named like it, an action), or None when no rule matches."""
        found = self.matching(type_id, name, path)
        if not found:
            return None
        if len(found) > 1:
            self.overlaps.setdefault(tuple(r.key for r in found), []).append(path)
        rule = found[0]
        self.used.add(rule.key)
        if kind in _LEAF_KINDS:
            self.leaf_keys.add(rule.key)
        else:
            what = f"the {kind.value.lower()} {type_id} '{path}'"
            self.non_leaves.append((rule.key, f"the SubTree '{path}'" if kind is NodeKind.SUBTREE else what))
        if rule.config is None:
            return dataclasses.replace(self._target(rule), name=type_id)
        factory = functools.partial(_test_node, config=rule.config)
        return NodeSpec(type_id, NodeKind.ACTION, (), factory,
                        f"TestNode '{rule.config.name}' of {self.rules.where(rule)}")

    def warnings(self) -> list[str]:
        """One sentence per group of rules that matched the same nodes, and per rule that matched no node."""
        lines = []
        by_key = {r.key: r for r in self.rules.rules}
        for keys, paths in self.overlaps.items():
            listed = " and ".join(f"'{k}' (line {by_key[k].line})" for k in keys)
            nodes = ", ".join(paths[:3]) + (f" and {len(paths) - 3} more" if len(paths) > 3 else "")
            lines.append(f"{self.rules.source}: rules {listed} all match {nodes}; the first in the file applies "
                         "(BT.CPP keeps its rules in an unordered map: which one it applies is unspecified)")
        for key, what in self.non_leaves:
            if key in self.leaf_keys:  # Nav2 names its RecoveryNode ComputePathToPose, like the leaf in it
                lines.append(f"{self.rules.where(by_key[key])}: rule '{key}' replaces leaves and also {what} (a rule's "
                             "key matches a node's name too, as in BT.CPP), whose children are then left out of the "
                             f"tree; '{key}::*' would match only the unnamed leaves of type {key}")
        for rule in self.rules.rules:
            if rule.key not in self.used and not any(rule.key in keys for keys in self.overlaps):
                lines.append(f"{self.rules.where(rule)}: rule '{rule.key}' matches no node of this tree")
        return lines


def _test_node(ctx: NodeContext, config: TestNodeConfig) -> BtNode:
    return TestNode(ctx, config)
