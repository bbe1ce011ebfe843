"""Dry runs with no set-up: every robot leaf replaced by a stand-in, the walk recorded tick by tick.

``bt-grasp tree run --dry FILE`` needs no robot, camera or flag: each leaf whose spec ``needs_robot`` is built
as a :class:`StandIn` with the same type, name, path and ports. A stand-in succeeds by default; outcome rules
steer it::

    PlanGrasp=failure:IK_UNREACHABLE      every PlanGrasp fails with that reason (a leaf type ...)
    pick/attempt/Lift=running:3           ... or a node's name or full path: RUNNING 3 ticks, then SUCCESS
    Grasp=failure                         the leaf's first declared failure reason

and a seeded random mode (``seed``) draws each robot leaf's outcome at the start of every attempt among
SUCCESS and the leaf's declared failure reasons, from one generator, so the same seed walks the same way.
A leaf's failure reasons are those its spec declares (:attr:`NodeSpec.failure_reasons`: ``@action(reasons=...)``
for a plugin's leaf, the robot leaves' declarations in ``bt_grasp.behaviours.library``), so a new leaf, or a
user's, gets its reasons here with no table to edit; a leaf that declares none may fail with any reason the
registry knows.
Control, decorator and script nodes are never replaced; a non-robot leaf only when an outcome rule names
it (then it becomes a stand-in too, with the same ports).

A stand-in does what the real leaf promises to the nodes downstream: on SUCCESS it writes every output
port with a typed placeholder (the :class:`StandInCatalog` says which, e.g. a list of detections, since
port types alone are ``object``); on FAILURE it reports the reason through :meth:`Leaf.fail`, which
writes ``failure_reason`` and ``failed_leaf`` as real leaves do. Like a robot leaf it does one control
period of work per tick.

:class:`DryRun` ticks the tree with a simulated clock and keeps, per tick and per root execution, every
status a node returned, in tree order (:class:`TickWalk`).
"""

from __future__ import annotations

import dataclasses
import enum
import random
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from bt_grasp.clock import ManualClock
from bt_grasp.errors import InputError
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.loader import LoadedTree, load_tree
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import NodeKind, NodeRegistry, NodeSpec, PortDirection, PortSpec

_LEAF_KINDS = (NodeKind.ACTION, NodeKind.CONDITION)
_SYNTAX = "NAME=success, NAME=failure[:REASON] or NAME=running:N"


class StandInCatalog(Protocol):
    """What the application knows about its robot leaves' outputs, for their stand-ins."""

    def placeholder(self, spec: NodeSpec, port: PortSpec) -> object:
        """The value a stand-in writes to an output port on SUCCESS (typed like the real leaf's)."""
        ...


class TypedPlaceholders:
    """A catalog that knows nothing about particular leaves: placeholders by port type only."""

    def placeholder(self, spec: NodeSpec, port: PortSpec) -> object:
        return type_placeholder(port, spec.name)


@dataclass(frozen=True)
class StandInValue:
    """What a stand-in writes to an ``object`` port nobody but other stand-ins reads (a grasp plan)."""

    leaf: str
    port: str

    def __str__(self) -> str:
        return f"<{self.port} from a {self.leaf} stand-in>"


def type_placeholder(port: PortSpec, leaf: str = "") -> object:
    """A value of the port's type: 0, 0.0, False, ``""``, the type's ``from_port_text("0;0")``, else (an
    ``object`` port) a :class:`StandInValue`."""
    simple: dict[type, object] = {int: 0, float: 0.0, bool: False, str: ""}
    if port.type in simple:
        return simple[port.type]
    parse = getattr(port.type, "from_port_text", None)
    if parse is not None:
        return parse("0;0")
    return StandInValue(leaf, port.name)


class OutcomeKind(enum.Enum):
    SUCCESS = "success"
    FAILURE = "failure"
    RUNNING = "running"


@dataclass(frozen=True)
class Outcome:
    """What a stand-in does in one attempt: RUNNING ``running_ticks`` ticks, then SUCCESS, or FAILURE with
    ``reason`` (None: the leaf's first declared reason)."""

    kind: OutcomeKind = OutcomeKind.SUCCESS
    reason: str | None = None
    running_ticks: int = 0


@dataclass(frozen=True)
class OutcomeRule:
    """``target=outcome``; ``target`` is a leaf type, a node name or a node's full path (exact)."""

    target: str
    outcome: Outcome
    text: str

    def matches(self, node_type: str, name: str, path: str) -> bool:
        return self.target in (node_type, name, path)


def parse_outcome(text: str) -> OutcomeRule:
    """One ``--outcome`` value; an :class:`InputError` (one sentence) when it is malformed."""
    where = f"--outcome '{text}'"
    target, sep, value = (part.strip() for part in text.partition("="))
    if not sep or not target or not value:
        raise InputError(where, f"is not {_SYNTAX}")
    head, _, tail = value.partition(":")
    head = head.strip().lower()
    if head == "success" and not tail:
        return OutcomeRule(target, Outcome(), text)
    if head == "failure" and ":" not in tail:
        return OutcomeRule(target, Outcome(OutcomeKind.FAILURE, tail.strip() or None), text)
    if head == "running" and tail.strip().isdigit():
        return OutcomeRule(target, Outcome(OutcomeKind.RUNNING, running_ticks=int(tail)), text)
    raise InputError(where, f"the outcome must be {_SYNTAX}")


@dataclass
class DryRunPlan:
    """How the stand-ins behave: outcome rules, the random seed (None: no random mode), the catalog of output
    placeholders, and the names of the reasons the registry knows (to check a rule's reason when a leaf declares
    none)."""

    rules: tuple[OutcomeRule, ...] = ()
    seed: int | None = None
    catalog: StandInCatalog = field(default_factory=TypedPlaceholders)
    known_reasons: frozenset[str] = frozenset()
    rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    def rule_for(self, node_type: str, name: str, path: str) -> OutcomeRule | None:
        for rule in self.rules:
            if rule.matches(node_type, name, path):
                return rule
        return None

    def reasons(self, spec: NodeSpec) -> tuple[str, ...]:
        """The reasons a stand-in for ``spec`` may fail with: the leaf's declared ones, else every known one."""
        return spec.failure_reasons or tuple(sorted(self.known_reasons))


class StandIn(Leaf):
    """A robot leaf's stand-in: same type, name, ports; outcome from the plan (see the module)."""

    def __init__(self, ctx: NodeContext, plan: DryRunPlan, original: NodeSpec) -> None:
        super().__init__(ctx)
        self.plan = plan
        self.original = original
        self.rule = plan.rule_for(original.name, ctx.name, ctx.path)
        self._bt_once_per_period = True  # like a robot leaf: one control period of work per tick
        self.outcome = Outcome()
        self.running_left = 0

    def _draw(self) -> Outcome:
        if self.rule is not None:
            return self.rule.outcome
        if self.plan.seed is None:
            return Outcome()
        choices = ("", *self.plan.reasons(self.original))
        pick = self.plan.rng.choice(choices)
        return Outcome(OutcomeKind.FAILURE, pick) if pick else Outcome()

    def initialise(self) -> None:
        self.outcome = self._draw()
        self.running_left = self.outcome.running_ticks

    def update(self) -> BtStatus:
        if self.running_left > 0:
            self.running_left -= 1
            return BtStatus.RUNNING
        if self.outcome.kind is OutcomeKind.FAILURE:
            declared = self.original.failure_reasons
            reason = self.outcome.reason or (declared[0] if declared else None)
            if reason is None:  # a leaf that declares no reason (Script) fails as it would: without one
                self.feedback_message = f"stand-in for {self.name} was told to fail"
                return BtStatus.FAILURE
            return self.fail(reason, f"stand-in for {self.name} was told to fail with {reason}")
        for port in self.original.ports:
            if port.direction is not PortDirection.INPUT and self.ports.has(port.name) and self.ports.key(port.name):
                self.ports.set(port.name, self.plan.catalog.placeholder(self.original, port))
        return BtStatus.SUCCESS


def stand_in_spec(spec: NodeSpec, plan: DryRunPlan, real: frozenset[str] = frozenset()) -> NodeSpec:
    """``spec`` with a stand-in factory (same name, kind, ports and ``needs_robot``). A robot leaf is a stand-in
    unless its type is in ``real``; any other leaf only where an outcome rule names it (its type, name or path)."""
    original = spec.factory
    assert original is not None
    robot = spec.needs_robot and spec.name not in real

    def factory(ctx: NodeContext) -> BtNode:
        if robot or plan.rule_for(spec.name, ctx.name, ctx.path) is not None:
            return StandIn(ctx, plan, spec)
        return original(ctx)

    return dataclasses.replace(spec, factory=factory)


def dry_registry(registry: NodeRegistry, plan: DryRunPlan, real: frozenset[str] = frozenset()) -> NodeRegistry:
    """A registry whose robot leaves are stand-ins, but those whose type is in ``real`` (the caller sets them up
    with what they need, e.g. ``tree run --dry --camera``'s perception leaves), and, when the plan has rules, the
    leaves they name; every other node type, the scripting enums and the failure reasons as in ``registry``."""
    specs = [
        stand_in_spec(s, plan, real) if s.kind in _LEAF_KINDS and (s.needs_robot or plan.rules) else s
        for s in registry.specs()
    ]
    return registry.with_specs(specs)


def known_reason_names(registry: NodeRegistry) -> frozenset[str]:
    """Every reason name the registry knows (built-in and plugins' reasons; a leaf declares only those)."""
    return frozenset(r.name for r in registry.reasons())


def _check_rules(tree: LoadedTree, plan: DryRunPlan) -> None:
    """Every rule names a leaf of the tree, and a failure reason it declares: InputError otherwise."""
    leaves = [n for n in tree.nodes() if n.bt_kind in _LEAF_KINDS]
    for rule in plan.rules:
        where = f"--outcome '{rule.text}'"
        matched = [n for n in leaves if rule.matches(n.bt_type, n.name, n.bt_path)]
        if not matched:
            names = sorted({n.bt_type for n in leaves if isinstance(n, StandIn)})
            raise InputError(
                where, f"'{rule.target}' is no leaf type, name or path of this tree (robot leaves: {', '.join(names)})"
            )
        reason = rule.outcome.reason
        for node in matched:
            declared = node.original.failure_reasons if isinstance(node, StandIn) else ()
            if reason is not None and declared and reason not in declared:
                raise InputError(
                    where, f"{node.bt_type} does not fail with {reason}; it declares {', '.join(declared)}"
                )


@dataclass(frozen=True)
class Step:
    """One status a node returned: its full path, type, depth in the tree and the status."""

    path: str
    node_type: str
    depth: int
    status: str


@dataclass
class TickWalk:
    """What one tick (control period) walked: the root's status and, per root execution, the statuses the
    nodes returned in tree order."""

    tick: int
    status: str
    runs: list[list[Step]] = field(default_factory=list)

    def as_json(self) -> dict[str, object]:
        return {
            "tick": self.tick,
            "status": self.status,
            "runs": [[{"path": s.path, "type": s.node_type, "status": s.status} for s in run] for run in self.runs],
        }


class _Walker:
    """The nodes' ``bt_listener``: collects each return as (preorder index, Step), grouped by root run."""

    def __init__(self, tree: LoadedTree) -> None:
        self.order: dict[int, tuple[int, int]] = {}
        self._index(tree.root, 0)
        self.root_uid = tree.root.bt_uid
        self.runs: list[list[tuple[int, Step]]] = [[]]
        for node in tree.nodes():
            node.bt_listener = self

    def _index(self, node: BtNode, depth: int) -> None:
        self.order[node.bt_uid] = (len(self.order), depth)
        for child in node.children:
            if isinstance(child, BtNode):
                self._index(child, depth + 1)

    def __call__(self, node: BtNode, before: BtStatus, result: BtStatus) -> None:
        index, depth = self.order[node.bt_uid]
        self.runs[-1].append((index, Step(node.bt_path, node.bt_type, depth, result.value)))
        if node.bt_uid == self.root_uid:
            self.runs.append([])

    def take(self) -> list[list[Step]]:
        runs = [[step for _, step in sorted(run, key=lambda item: item[0])] for run in self.runs if run]
        self.runs = [[]]
        return runs


@dataclass
class DryRunResult:
    status: BtStatus
    ticks: int
    walk: list[TickWalk]
    blackboard: dict[str, object]


def load_dry(
    path: Path,
    registry: NodeRegistry,
    plan: DryRunPlan,
    *,
    substitutions: Mapping[str, str] | None = None,
    clock: ManualClock | None = None,
    real: frozenset[str] = frozenset(),
) -> LoadedTree:
    """Load ``path`` with robot leaves as stand-ins (but the types in ``real``), plus the other leaves the plan's
    rules name. A rule that names no leaf of the tree, or a reason the leaf does not declare: InputError (one
    sentence)."""
    for rule in plan.rules:
        reason = rule.outcome.reason
        if reason is not None and plan.known_reasons and reason not in plan.known_reasons:
            raise InputError(f"--outcome '{rule.text}'", f"{reason} is not a failure reason bt_grasp knows")
    tree = load_tree(path, dry_registry(registry, plan, real), substitutions=substitutions, clock=clock)
    _check_rules(tree, plan)
    return tree


def run_dry(tree: LoadedTree, clock: ManualClock, max_ticks: int, dt_s: float) -> DryRunResult:
    """Tick ``tree`` until it completes or ``max_ticks``, advancing ``clock`` by ``dt_s`` between ticks."""
    walker = _Walker(tree)
    walk: list[TickWalk] = []
    status = BtStatus.IDLE
    for tick in range(1, max_ticks + 1):
        status = tree.tick()
        walk.append(TickWalk(tick, status.value, walker.take()))
        if status in (BtStatus.SUCCESS, BtStatus.FAILURE, BtStatus.SKIPPED):
            break
        clock.advance_s(dt_s)
    if not status.completed:
        tree.halt()
    return DryRunResult(status, len(walk), walk, tree.blackboard_values())


def format_walk(walk: Iterable[TickWalk]) -> list[str]:
    """Readable lines: ``tick N: STATUS`` then, per root execution, each node's status indented by depth."""
    lines = []
    for tick in walk:
        runs = f" ({len(tick.runs)} runs)" if len(tick.runs) > 1 else ""
        lines.append(f"tick {tick.tick}: {tick.status}{runs}")
        for number, run in enumerate(tick.runs, 1):
            if len(tick.runs) > 1:
                lines.append(f"  run {number}:")
            pad = "    " if len(tick.runs) > 1 else "  "
            lines.extend(f"{pad}{'  ' * s.depth}{s.path.rsplit('/', 1)[-1]} [{s.node_type}] {s.status}" for s in run)
    return lines
