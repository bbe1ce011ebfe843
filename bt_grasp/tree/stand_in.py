"""A dry run's stand-in leaves: what they do call by call, and what they write (see :mod:`bt_grasp.tree.dry_run`).

:class:`StandIn` replaces a leaf that needs the robot (or one an ``--outcome``/``--output-port`` names) with the same
type, name, path and ports; :class:`ModelStandIn` is the node a TreeNodesModel declares and nothing registered.
Their outcomes come from the :class:`DryRunPlan` (:mod:`bt_grasp.tree.outcomes`: one per call, the last repeating;
or drawn from a seed); what they write to their output ports from the plan's given values, else from the
:class:`StandInCatalog` (a robot leaf's stand-in, on SUCCESS) or the port's type (a model's, at every completion).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Protocol

from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.node import BtStatus
from bt_grasp.tree.outcomes import Outcome, OutcomeKind, OutcomeRule, OutputRule
from bt_grasp.tree.registry import NodeSpec, PortDirection, PortSpec
from bt_grasp.tree.values import convert_text


class StandInCatalog(Protocol):
    """What the application knows about its robot leaves' outputs, for their stand-ins."""

    def placeholder(self, node: StandIn, port: PortSpec) -> object:
        """The value ``node`` (a stand-in; ``node.original`` is the real leaf's spec, ``node.ports`` its inputs)
        writes to an output port on SUCCESS, typed like the real leaf's. May raise :class:`StandInRefusal`."""
        ...


class StandInRefusal(Exception):
    """Raised by a catalog when the real leaf would fail with these inputs: the stand-in fails with ``reason``."""

    def __init__(self, reason: str, sentence: str) -> None:
        super().__init__(sentence)
        self.reason = reason
        self.sentence = sentence


class TypedPlaceholders:
    """A catalog that knows nothing about particular leaves: placeholders by port type only."""

    def placeholder(self, node: StandIn, port: PortSpec) -> object:
        return type_placeholder(port, node.original.name)


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


@dataclass
class DryRunPlan:
    """How the stand-ins behave: outcome rules, the random seed (None: no random mode), the catalog of output
    placeholders, the names of the reasons the registry knows (to check a rule's reason when a leaf declares
    none), and the output-port values given."""

    rules: tuple[OutcomeRule, ...] = ()
    seed: int | None = None
    catalog: StandInCatalog = field(default_factory=TypedPlaceholders)
    known_reasons: frozenset[str] = frozenset()
    outputs: tuple[OutputRule, ...] = ()
    rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    def rule_for(self, node_type: str, name: str, path: str) -> OutcomeRule | None:
        for rule in self.rules:
            if rule.matches(node_type, name, path):
                return rule
        return None

    def outputs_for(self, node_type: str, name: str, path: str) -> dict[str, OutputRule]:
        """The given output-port values of a node, by port (the first rule per port)."""
        found: dict[str, OutputRule] = {}
        for rule in self.outputs:
            if rule.matches(node_type, name, path):
                found.setdefault(rule.port, rule)
        return found

    def names(self, node_type: str, name: str, path: str) -> bool:
        """An outcome or an output value names the node: it becomes a stand-in."""
        return self.rule_for(node_type, name, path) is not None or bool(self.outputs_for(node_type, name, path))

    def reasons(self, spec: NodeSpec) -> tuple[str, ...]:
        """The reasons a stand-in for ``spec`` may fail with: the leaf's declared ones, else every known one."""
        return spec.failure_reasons or tuple(sorted(self.known_reasons))


class StandIn(Leaf):
    """A stand-in for a leaf: same type, name, ports; its outcome call by call from the plan (see the module)."""

    #: a model's stand-in writes its outputs at every completion; a robot leaf's on SUCCESS only
    writes_on_failure = False

    def __init__(self, ctx: NodeContext, plan: DryRunPlan, original: NodeSpec) -> None:
        super().__init__(ctx)
        self.plan = plan
        self.original = original
        self.rule = plan.rule_for(original.name, ctx.name, ctx.path)
        self.given = plan.outputs_for(original.name, ctx.name, ctx.path)
        self._bt_once_per_period = True  # like a robot leaf: one control period of work per tick
        self.outcome = Outcome()
        self.running_left = 0
        #: calls started so far (each start from IDLE is one)
        self.calls = 0

    def _draw(self) -> Outcome:
        if self.rule is not None:
            return self.rule.for_call(self.calls)
        if self.plan.seed is None:
            return Outcome()
        choices = ("", *self.random_reasons())
        pick = self.plan.rng.choice(choices)
        return Outcome(OutcomeKind.FAILURE, pick or None) if pick else Outcome()

    def random_reasons(self) -> tuple[str, ...]:
        return self.plan.reasons(self.original)

    def initialise(self) -> None:
        self.outcome = self._draw()
        self.running_left = self.outcome.running_ticks
        self.call = self.calls
        self.calls += 1

    def update(self) -> BtStatus:
        if self.running_left > 0:
            self.running_left -= 1
            return BtStatus.RUNNING
        failing = self.outcome.kind is OutcomeKind.FAILURE
        try:
            self._write_outputs(succeeded=not failing)
        except StandInRefusal as refusal:
            return self.fail(refusal.reason, refusal.sentence)
        if failing:
            declared = self.original.failure_reasons
            reason = self.outcome.reason or (declared[0] if declared else None)
            if reason is None:  # a leaf that declares no reason (Script) fails as it would: without one
                self.feedback_message = f"stand-in for {self.name} was told to fail"
                return BtStatus.FAILURE
            return self.fail(reason, f"stand-in for {self.name} was told to fail with {reason}")
        return BtStatus.SUCCESS

    def _write_outputs(self, *, succeeded: bool) -> None:
        for port in self.original.ports:
            if port.direction is PortDirection.INPUT or not self.ports.has(port.name):
                continue
            given = self.given.get(port.name)
            if given is not None:
                self.ports.set(port.name, output_value(port, given.for_call(self.call)))
            elif succeeded or self.writes_on_failure:
                self.ports.set(port.name, self.default_output(port))

    def default_output(self, port: PortSpec) -> object:
        return self.plan.catalog.placeholder(self, port)


class ModelStandIn(StandIn):
    """A stand-in for a node only a TreeNodesModel declares: it writes every connected output port at every
    completion, its type's default unless a value is given; ``--random`` draws SUCCESS or FAILURE (no reason:
    another project's node reports none of bt_grasp's)."""

    writes_on_failure = True

    def default_output(self, port: PortSpec) -> object:
        return type_placeholder(port, self.original.name)

    def _draw(self) -> Outcome:
        if self.rule is not None or self.plan.seed is None:
            return super()._draw()
        return Outcome(OutcomeKind.FAILURE) if self.plan.rng.choice((False, True)) else Outcome()


def output_value(port: PortSpec, text: str) -> object:
    """A given output value as the port's type (text for an ``object`` port)."""
    return convert_text(text, port.type)
