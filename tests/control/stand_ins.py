"""Stand-in leaves and a stepper for control tests: no simulator, a manual clock, one tree.

The tree (ticks written out in the tests that use it)::

    Sequence main
      See                        SUCCESS at once; objects = [red at x 0.1, blue at x 0.2], target = objects[0]
      RetryUntilSuccessful(3)
        Check height={height}    FAILURE FLAKY on its first attempt (retried within tick 1); then FAILURE TOO_LOW
                                 when height < 0.05, else SUCCESS
      Move target height mode    RUNNING for round(height * 100) ticks, then SUCCESS; moved = target's label

With ``height = 0.05`` (the default set by :func:`build`) the run is 5 ticks: tick 1 See SUCCESS, Check FAILURE
FLAKY then SUCCESS, Move RUNNING (1 of 5); ticks 2-4 Move RUNNING; tick 5 Move SUCCESS. The clock advances 10 ms
after every tick but the last: after tick t it reads (t - 1) * 10 ms.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_grasp.clock import ManualClock
from bt_grasp.control import Controller
from bt_grasp.nodes import Leaf, Status, action, input_port, output_port
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string
from bt_grasp.tree.runner import RunOutcome, TickGate, TreeRunner

STEP_NS = 10_000_000  # 10 ms a tick


@dataclass(frozen=True)
class Det:
    label: str
    centroid_base_m: tuple[float, float, float]
    size_m: tuple[float, float, float] = (0.05, 0.05, 0.05)


class Stepper:
    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.steps = 0

    def step(self, n: int = 1) -> None:
        self.steps += n
        self.clock.advance_ns(STEP_NS * n)

    def now_ns(self) -> int:
        return self.clock.now_ns()


def _registry() -> Any:
    registry = builtin_registry()

    @action(ports=[
        output_port("objects", object, "every object", default="{objects}"),
        output_port("target", object, "the first one", default="{target}"),
    ])
    class See(Leaf):
        def update(self) -> Status:
            objects = [Det("red", (0.1, 0.0, 0.0)), Det("blue", (0.2, 0.0, 0.0))]
            self.ports.set("objects", objects)
            self.ports.set("target", objects[0])
            return Status.SUCCESS

    @action(ports=[input_port("height", float, "{height}", "m")])
    class Check(Leaf):
        def setup(self, **kwargs: Any) -> None:
            self.calls = 0

        def update(self) -> Status:
            self.calls += 1
            if self.calls == 1:
                return self.fail("FLAKY", "the first check always fails")
            if self.ports.require("height", float) < 0.05:
                return self.fail("TOO_LOW", "the height is under 5 cm")
            return Status.SUCCESS

    @action(ports=[
        input_port("target", object, "{target}", "what to move"),
        input_port("height", float, "{height}", "m"),
        input_port("mode", str, "{mode}", "how", choices=("fast", "slow")),
        output_port("done", object, "the label moved", default="{moved}"),
    ])
    class Move(Leaf):
        def initialise(self) -> None:
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            if self.ticks < round(self.ports.require("height", float) * 100):
                return Status.RUNNING
            self.ports.set("done", self.ports.require("target").label)
            return Status.SUCCESS

    registry.register(See)
    registry.register(Check)
    registry.register(Move)
    return registry


TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence name="main">
      <See/>
      <RetryUntilSuccessful num_attempts="3"><Check/></RetryUntilSuccessful>
      <Move mode="{mode}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def build(height: float = 0.05) -> tuple[LoadedTree, Stepper]:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, _registry(), clock=clock)
    tree.root_blackboard.set("height", height)
    tree.root_blackboard.set("mode", "fast")
    for node in tree.nodes():
        node.setup()
    return tree, Stepper(clock)


def run(tree: LoadedTree, stepper: Stepper, gate: TickGate | None = None, max_ticks: int = 50
        ) -> tuple[RunOutcome, list[dict[str, Any]]]:
    runner = TreeRunner(tree, stepper, steps_per_tick=1, gate=gate)
    outcome = runner.run(max_ticks)
    if isinstance(gate, Controller):
        gate.finish()
    return outcome, runner.stream
