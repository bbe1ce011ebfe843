"""The run loop: failures inside one tick are all seen, retries mean 'tried again after failing'."""

from __future__ import annotations

from typing import Any

from bt_grasp.clock import ManualClock
from bt_grasp.nodes import Leaf, NodeRegistry, Status, action
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.loader import load_tree_from_string
from bt_grasp.tree.runner import TreeRunner


class Stepper:
    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.dt_s = 0.002

    def step(self, n: int = 1) -> None:
        self.clock.advance_ns(2_000_000 * n)

    def now_ns(self) -> int:
        return self.clock.now_ns()


class Recorder:
    def __init__(self) -> None:
        self.ticks: list[dict[str, Any]] = []
        self.events: list[dict[str, Any]] = []
        self.flushes = 0

    def write_tick(self, tick: int, stamp_ns: int, nodes: Any, blackboard: Any, robot: Any = None) -> None:
        self.ticks.append({"tick": tick, "nodes": {n["name"]: (n["status"], n["ticked"]) for n in nodes}})

    def write_event(self, stamp_ns: int, kind: str, payload: Any) -> None:
        self.events.append(dict(payload))

    def flush_tick(self) -> None:
        self.flushes += 1


def _registry() -> NodeRegistry:
    registry = builtin_registry()

    @action()
    class FailTwice(Leaf):
        """FAILURE (FLAKY) on the first two attempts, then SUCCESS; each attempt finishes at once."""

        def setup(self, **kwargs: Any) -> None:
            self.calls = 0

        def update(self) -> Status:
            self.calls += 1
            return self.fail("FLAKY", f"attempt {self.calls} failed") if self.calls <= 2 else Status.SUCCESS

    @action()
    class Slow(Leaf):
        """RUNNING for two ticks, then SUCCESS."""

        def initialise(self) -> None:
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            return Status.SUCCESS if self.ticks >= 3 else Status.RUNNING

    registry.register(FailTwice)
    registry.register(Slow)
    return registry


TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence>
      <RetryUntilSuccessful num_attempts="5"><FailTwice/></RetryUntilSuccessful>
      <Slow/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_failures_within_one_tick_and_retries() -> None:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, _registry(), clock=clock)
    for node in tree.nodes():
        node.setup()
    recorder = Recorder()
    outcome = TreeRunner(tree, Stepper(clock), steps_per_tick=5, recorder=recorder).run(max_ticks=10)
    # tick 1: FailTwice fails, fails, succeeds: the retry yields after each synchronous failure and the root
    #         runs again at once (BT.CPP's wake-up), 3 root executions within the tick; Slow RUNNING
    # tick 2: Slow RUNNING; tick 3: Slow SUCCESS -> Sequence SUCCESS
    assert outcome.status == "SUCCESS" and outcome.ticks == 3
    assert [(f.tick, f.leaf, f.reason) for f in outcome.failures] == [(1, "FailTwice", "FLAKY")] * 2
    assert outcome.retries == {"FailTwice::3": 2}  # by path (BT.CPP's fullPath), the node's name everywhere
    assert [e["message"] for e in recorder.events if "message" in e] == ["attempt 1 failed", "attempt 2 failed"]
    assert [e for e in recorder.events if "runs" in e] == [{"tick": 1, "runs": 3}]
    assert outcome.root_runs == 5
    assert recorder.ticks[0]["nodes"]["FailTwice"] == ("SUCCESS", True)
    assert recorder.ticks[1]["nodes"]["FailTwice"][1] is False  # not ticked on tick 2
    assert recorder.ticks[1]["nodes"]["Slow"] == ("RUNNING", True)
    assert recorder.flushes == 3
    assert abs(outcome.sim_time_s - 0.02) < 1e-12  # two control periods stepped between three ticks
