"""Dry runs with no set-up: leaves stood in for, steered as BehaviorTree.CPP tests steer theirs, the walk recorded.

``bt-grasp tree run --dry FILE`` needs no robot, camera or flag. What is stood in for:

* every leaf whose spec ``needs_robot`` (bt_grasp's robot leaves, a plugin's), as a :class:`StandIn` with the same
  type, name, path and ports (but the types in ``real``: ``tree run --dry --camera`` runs those for real);
* every action and condition a ``<TreeNodesModel>`` declares (the tree's own, its includes', a ``--nodes-model``
  file's) and nothing registered, as a :class:`ModelStandIn` with the model's ports
  (:mod:`bt_grasp.tree.model_stand_ins`);
* any other leaf an ``--outcome`` or ``--output-port`` names;
* any node a BT.CPP substitution-rule file's rule matches, as BT.CPP's ``TestNode`` or the registered leaf the rule
  names (:mod:`bt_grasp.tree.test_node`), before anything else is considered.

A stand-in succeeds, call after call, unless told otherwise (:mod:`bt_grasp.tree.outcomes`: ``--outcome
NAME=failure,failure,success``, the last repeating); ``seed`` draws each robot leaf's outcome at every call
among SUCCESS and the reasons the leaf declares (:attr:`NodeSpec.failure_reasons`; a leaf that declares none may
fail with any reason the registry knows), from one generator, so the same seed walks the same way.

What a stand-in writes: on SUCCESS, a robot leaf's stand-in writes to each connected output port what the real
leaf promises (the :class:`StandInCatalog`: e.g. a list of detections); a model's stand-in writes every connected
output port at every completion, SUCCESS or FAILURE, as other projects' nodes write their error codes either way:
its type's default (0, 0.0, false, "", else a :class:`StandInValue`). A value given with ``--output-port
NAME.PORT=VALUE[,VALUE...]`` is written at every completion of that call, by any stand-in. On FAILURE a stand-in
reports the reason through :meth:`Leaf.fail` (``failure_reason``, ``failed_leaf``) as real leaves do. Like a robot
leaf it does one control period of work per tick.

:func:`run_dry` ticks the tree on a simulated clock and records the walk as BT.CPP's loggers show it
(:mod:`bt_grasp.tree.walk`): every status change of every node in order, halts included.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.clock import ManualClock
from bt_grasp.errors import InputError, did_you_mean
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.formats.document import ModelDecl
from bt_grasp.tree.loader import LoadedTree, build_tree, read_tree_file
from bt_grasp.tree.model_stand_ins import model_specs
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.outcomes import has_wildcard
from bt_grasp.tree.registry import Factory, NodeKind, NodeRegistry, NodeSpec, PortDirection
from bt_grasp.tree.rules_file import RuleFile
from bt_grasp.tree.stand_in import (
    DryRunPlan,
    ModelStandIn,
    StandIn,
    StandInCatalog,
    StandInRefusal,
    StandInValue,
    TypedPlaceholders,
    output_value,
    type_placeholder,
)
from bt_grasp.tree.test_node import RuleSet, TestNode
from bt_grasp.tree.walk import TickSummary, Transition, WalkRecorder

logger = logging.getLogger(__name__)

_LEAF_KINDS = (NodeKind.ACTION, NodeKind.CONDITION)


def stand_in_spec(spec: NodeSpec, plan: DryRunPlan, real: frozenset[str] = frozenset()) -> NodeSpec:
    """``spec`` with a stand-in factory (same name, kind, ports and ``needs_robot``). A robot leaf is a stand-in
    unless its type is in ``real``; any other leaf only where an outcome or output value names it."""
    original = spec.factory
    assert original is not None
    robot = spec.needs_robot and spec.name not in real

    def factory(ctx: NodeContext) -> BtNode:
        if robot or plan.names(spec.name, ctx.name, ctx.path):
            return StandIn(ctx, plan, spec)
        return original(ctx)

    return dataclasses.replace(spec, factory=factory)


def _model_factory(plan: DryRunPlan) -> Callable[[NodeSpec], Factory]:
    def make(spec: NodeSpec) -> Factory:
        def factory(ctx: NodeContext) -> BtNode:
            return ModelStandIn(ctx, plan, spec)

        return factory

    return make


def dry_registry(registry: NodeRegistry, plan: DryRunPlan, real: frozenset[str] = frozenset(),
                 models: Sequence[ModelDecl] = ()) -> NodeRegistry:
    """A registry whose robot leaves are stand-ins, but those whose type is in ``real`` (the caller sets them up
    with what they need, e.g. ``tree run --dry --camera``'s perception leaves), whose other leaves are stand-ins
    where the plan names them, plus a stand-in type for each action and condition of ``models`` nothing
    registered; every other node type, the scripting enums and the failure reasons as in ``registry``."""
    naming = bool(plan.rules or plan.outputs)
    specs = [
        stand_in_spec(s, plan, real) if s.kind in _LEAF_KINDS and (s.needs_robot or naming) else s
        for s in registry.specs()
    ]
    stood_in = model_specs(models, lambda name: name in registry, _model_factory(plan))
    dry = registry.with_specs([*specs, *(spec for spec, _ in stood_in)])
    dry.origins.update((spec.name, origin) for spec, origin in stood_in)
    return dry


def known_reason_names(registry: NodeRegistry) -> frozenset[str]:
    """Every reason name the registry knows (built-in and plugins' reasons; a leaf declares only those)."""
    return frozenset(r.name for r in registry.reasons())


def _leaves(tree: LoadedTree) -> list[BtNode]:
    return [n for n in tree.nodes() if n.bt_kind in _LEAF_KINDS]


def _nothing_named(where: str, target: str, tree: LoadedTree) -> InputError:
    leaves = _leaves(tree)
    stood = sorted({n.bt_type for n in leaves if isinstance(n, StandIn)})
    names = sorted({n.bt_type for n in leaves} | {n.name for n in leaves})
    kind = "pattern" if has_wildcard(target) else "name"
    hint = "" if has_wildcard(target) else did_you_mean(target, names)
    return InputError(where, f"the {kind} '{target}' matches no leaf of this tree (by type, name or full path"
                      f"{'; stand-ins: ' + ', '.join(stood) if stood else ''}){hint}")


def _check_rules(tree: LoadedTree, plan: DryRunPlan) -> None:
    """Every outcome and output value names a leaf of the tree that is a stand-in (not a substitution rule's
    TestNode), with a failure reason it declares and an output port it has: InputError otherwise."""
    leaves = _leaves(tree)
    for rule in plan.rules:
        matched = [n for n in leaves if rule.matches(n.bt_type, n.name, n.bt_path)]
        if not matched:
            raise _nothing_named(rule.where, rule.target, tree)
        for node in matched:
            if not isinstance(node, StandIn):
                raise InputError(rule.where, f"{node.bt_type} '{node.bt_path}' is replaced by a substitution rule "
                                 f"({node.bt_spec.description}); steer it there, or leave the rule out")
            declared = node.original.failure_reasons
            for outcome in rule.outcomes:
                if outcome.reason is not None and declared and outcome.reason not in declared:
                    raise InputError(rule.where, f"{node.bt_type} does not fail with {outcome.reason}; it declares "
                                     f"{', '.join(declared)}")
    for output in plan.outputs:
        matched = [n for n in leaves if output.matches(n.bt_type, n.name, n.bt_path)]
        if not matched:
            raise _nothing_named(output.where, output.target, tree)
        for node in matched:
            if not isinstance(node, StandIn):
                raise InputError(output.where, f"{node.bt_type} '{node.bt_path}' is replaced by a substitution "
                                 "rule; write its outputs with the rule's success_script or failure_script")
            port = node.original.port(output.port)
            if port is None or port.direction is PortDirection.INPUT:
                outputs = [p.name for p in node.original.ports if p.direction is not PortDirection.INPUT]
                raise InputError(output.where, f"{node.bt_type} has no output port '{output.port}' (its output "
                                 f"ports: {', '.join(outputs) or 'none'}){did_you_mean(output.port, outputs)}")
            for text in output.values:
                try:
                    output_value(port, text)
                except TreeRuntimeError as exc:
                    raise InputError(output.where, f"'{text}' is not a {port.type_label} for port '{port.name}' of "
                                     f"{node.bt_type}: {exc}") from None


def _check_reasons(plan: DryRunPlan) -> None:
    for rule in plan.rules:
        for outcome in rule.outcomes:
            reason = outcome.reason
            if reason is not None and plan.known_reasons and reason not in plan.known_reasons:
                raise InputError(rule.where, f"{reason} is not a failure reason bt_grasp knows"
                                 f"{did_you_mean(reason, sorted(plan.known_reasons))}")


def load_dry(
    path: Path,
    registry: NodeRegistry,
    plan: DryRunPlan,
    *,
    substitutions: Mapping[str, str] | None = None,
    clock: ManualClock | None = None,
    real: frozenset[str] = frozenset(),
    rules: RuleFile | None = None,
    models: Sequence[ModelDecl] = (),
) -> LoadedTree:
    """Load ``path`` for a dry run (see the module): ``models`` are TreeNodesModel entries beyond the tree's own
    (``--nodes-model``), ``rules`` a BT.CPP substitution-rule file. An outcome, output value or ``--substitute``
    rule that names no node, or a reason the leaf does not declare: InputError (one sentence). Rules that overlap
    or match nothing are logged warnings."""
    _check_reasons(plan)
    document = read_tree_file(path)
    dry = dry_registry(registry, plan, real, [*document.models, *models])
    rule_set = RuleSet(rules, dry) if rules is not None else None
    tree = build_tree(document, dry, substitutions=substitutions, clock=clock, replacer=rule_set)
    for pattern, replacement in (substitutions or {}).items():
        if pattern not in tree.substituted:
            reach = ("a wildcard reaches the robot's leaves and those a plugin or TreeNodesModel brought; name "
                     "another leaf exactly") if any(c in pattern for c in "*?[") else "name a leaf's type, name or path"
            raise InputError(f"--substitute '{pattern}={replacement}'", f"replaces no leaf of this tree ({reach})")
    if rule_set is not None:
        for sentence in rule_set.warnings():
            logger.warning("%s", sentence)
    _check_rules(tree, plan)
    return tree


@dataclass
class DryRunResult:
    status: BtStatus
    ticks: int
    #: per tick: the root's status and its executions
    walk: list[TickSummary]
    #: every status change in order (BT.CPP's StatusChangeLogger), halts included
    transitions: list[Transition]
    blackboard: dict[str, object]
    tree: LoadedTree | None = None


def run_dry(tree: LoadedTree, clock: ManualClock, max_ticks: int, dt_s: float) -> DryRunResult:
    """Tick ``tree`` until it completes (or is SKIPPED) or ``max_ticks``, advancing ``clock`` by ``dt_s`` between
    ticks; a tree still RUNNING then is halted (as BT.CPP's ``Tree`` is when destroyed), its halts in the walk."""
    recorder = WalkRecorder(tree.root).attach(tree.nodes())
    start_ns = clock.now_ns()
    status = BtStatus.IDLE
    for tick in range(1, max_ticks + 1):
        recorder.start_tick(tick, clock.now_ns() - start_ns)
        status = tree.tick()
        recorder.end_tick(status, tree.runs)
        if status in (BtStatus.SUCCESS, BtStatus.FAILURE, BtStatus.SKIPPED):
            break
        clock.advance_s(dt_s)
    if not status.completed and status is not BtStatus.SKIPPED:
        tree.halt()
    return DryRunResult(status, len(recorder.ticks), recorder.ticks, recorder.transitions, tree.blackboard_values(),
                        tree)


__all__ = [
    "DryRunPlan", "DryRunResult", "ModelStandIn", "StandIn", "StandInCatalog", "StandInRefusal", "StandInValue",
    "TestNode", "TypedPlaceholders", "dry_registry", "known_reason_names", "load_dry", "run_dry", "type_placeholder",
]
