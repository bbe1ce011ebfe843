"""BT.CPP-style substitution rules: replace leaves by stand-ins when a tree runs without the robot.

A rule maps a glob, matched against a leaf's registration ID, instance name or full path, to either

* a registered leaf with no required ports: ``AlwaysSuccess``, ``AlwaysFailure``, ...; or
* a test behaviour: ``Success``, ``Failure``, ``Failure:NO_DETECTION`` (fails with that reason, which
  ``FailureIs`` sees), ``Running:3`` (RUNNING 3 ticks, then SUCCESS), ``Running:3:Failure[:REASON]``.

Rules apply to actions and conditions only; the first matching rule wins. A pattern with a wildcard
(``*``, ``?``, ``[``) replaces the leaves of other projects and of the robot: robot leaves, and leaves a plugin or a
TreeNodesModel brought (``Clear*=AlwaysFailure`` reaches Nav2's ``ClearEntireCostmap``); bt_grasp's and BT.CPP's
own logic leaves stay as written (``*=AlwaysSuccess`` leaves ``Script``, ``SetBlackboard`` and ``SelectObject``
alone); to replace one of those, name its type, name or path exactly (``Script=AlwaysSuccess``). A rule that
replaces no node of the tree is an error of the dry run (``bt_grasp.tree.dry_run``), never silently nothing.

BehaviorTree.CPP's own rule files (``--substitution-rules``) are :mod:`bt_grasp.tree.test_node`'s.
"""

from __future__ import annotations

import fnmatch
import functools
from collections.abc import Mapping
from dataclasses import dataclass

from bt_grasp.errors import InputError
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.node import BtStatus
from bt_grasp.tree.registry import NodeKind, NodeRegistry, NodeSpec

_LEAF_KINDS = (NodeKind.ACTION, NodeKind.CONDITION)


@dataclass(frozen=True)
class TestBehaviour:
    """What a TestNode does: RUNNING for ``running_ticks`` ticks, then ``result``; a FAILURE with a
    ``reason`` is reported through :meth:`Leaf.fail` (so ``FailureIs`` sees it)."""

    __test__ = False  # not a pytest test class

    running_ticks: int = 0
    result: BtStatus = BtStatus.SUCCESS
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

    def update(self) -> BtStatus:
        if self.ticks < self.behaviour.running_ticks:
            self.ticks += 1
            return BtStatus.RUNNING
        if self.behaviour.result == BtStatus.FAILURE and self.behaviour.reason:
            return self.fail(self.behaviour.reason, f"stand-in for {self.name} was told to fail")
        return self.behaviour.result


@dataclass(frozen=True)
class SubstitutionRule:
    pattern: str
    replacement: str
    spec: NodeSpec | None = None  # a registered replacement
    behaviour: TestBehaviour | None = None  # a test behaviour

    @property
    def wildcard(self) -> bool:
        return any(c in self.pattern for c in "*?[")

    def matches(self, type_id: str, name: str, path: str) -> bool:
        return any(fnmatch.fnmatchcase(text, self.pattern) for text in (type_id, name, path))

    def spec_for(self, original: NodeSpec) -> NodeSpec:
        if self.spec is not None:
            return self.spec
        assert self.behaviour is not None
        factory = functools.partial(_test_node, behaviour=self.behaviour)
        return NodeSpec("TestNode", original.kind, (), factory, f"stand-in: {self.replacement}")


def _test_node(ctx: NodeContext, behaviour: TestBehaviour) -> TestNode:
    return TestNode(ctx, behaviour)


def parse_test_behaviour(text: str) -> TestBehaviour | None:
    parts = [p.strip() for p in text.split(":")]
    head = parts[0].lower()
    if head == "success" and len(parts) == 1:
        return TestBehaviour(0, BtStatus.SUCCESS)
    if head == "failure" and len(parts) <= 2:
        return TestBehaviour(0, BtStatus.FAILURE, parts[1] if len(parts) == 2 and parts[1] else None)
    if head == "running" and 2 <= len(parts) <= 4 and parts[1].isdigit():
        ticks = int(parts[1])
        if len(parts) == 2:
            return TestBehaviour(ticks, BtStatus.SUCCESS)
        final = parts[2].lower()
        if final == "success" and len(parts) == 3:
            return TestBehaviour(ticks, BtStatus.SUCCESS)
        if final == "failure":
            return TestBehaviour(ticks, BtStatus.FAILURE, parts[3] if len(parts) == 4 and parts[3] else None)
    return None


def parse_rules(rules: Mapping[str, str] | None, registry: NodeRegistry) -> tuple[SubstitutionRule, ...]:
    """Check every rule; a bad one is an :class:`InputError` naming it."""
    parsed = []
    for pattern, replacement in (rules or {}).items():
        where = f"substitution '{pattern}={replacement}'"
        if not pattern:
            raise InputError(where, "the node pattern is empty")
        spec = registry.get(replacement)
        if spec is not None:
            if spec.kind not in _LEAF_KINDS:
                raise InputError(where, f"{replacement} is a {spec.kind.value}; only a leaf can stand in")
            if any(p.required for p in spec.ports):
                raise InputError(where, f"{replacement} needs ports, so it cannot stand in for another node")
            parsed.append(SubstitutionRule(pattern, replacement, spec=spec))
            continue
        behaviour = parse_test_behaviour(replacement)
        if behaviour is None:
            raise InputError(
                where,
                "the replacement must be a registered leaf (AlwaysSuccess, AlwaysFailure, ...) or "
                "Success, Failure[:REASON], Running:N, Running:N:Failure[:REASON]",
            )
        parsed.append(SubstitutionRule(pattern, replacement, behaviour=behaviour))
    return tuple(parsed)


def substitute(
    rules: tuple[SubstitutionRule, ...], spec: NodeSpec, type_id: str, name: str, path: str, *, foreign: bool
) -> tuple[SubstitutionRule, NodeSpec] | None:
    """The rule that replaces a leaf and the replacement spec, or None when no rule matches (or the node is not a
    leaf, or only a wildcard rule matches a leaf that is not ``foreign``: a robot leaf, or one a plugin or a
    TreeNodesModel brought)."""
    if spec.kind not in _LEAF_KINDS:
        return None
    for rule in rules:
        if rule.wildcard and not foreign:
            continue
        if rule.matches(type_id, name, path):
            return rule, rule.spec_for(spec)
    return None
