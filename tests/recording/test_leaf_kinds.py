"""Replay sees leaves as leaves: a real tree, recorded through the real introspection, read back.

The tree introspection writes a node's kind as ``NodeKind.value`` ("Action", "Condition", ...); the reader
once expected lowercase, so no node was a leaf and ``bt-grasp replay`` reported no retries per leaf.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_grasp.clock import ManualClock
from bt_grasp.nodes import Leaf, Status, action
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.replay import summary
from bt_grasp.recording.writer import RunRecorder
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.introspect import tree_structure
from bt_grasp.tree.loader import load_tree_from_string
from bt_grasp.tree.registry import NodeKind, NodeRegistry
from bt_grasp.tree.runner import TreeRunner

# FlakyReach: each attempt is RUNNING for one tick, then FAILURE (UNREACHABLE) on the first two attempts,
# SUCCESS on the third. Each failure sends the Fallback to the recovery, which runs two ticks and fails, so
# the RetryUntilSuccessful starts FlakyReach again on a later tick (the log sees every failure).
TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <RetryUntilSuccessful num_attempts="5">
      <Fallback>
        <FlakyReach/>
        <ForceFailure><Recover/></ForceFailure>
      </Fallback>
    </RetryUntilSuccessful>
  </BehaviorTree>
</root>
"""


class Stepper:
    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock

    def step(self, n: int = 1) -> None:
        self.clock.advance_ns(10_000_000 * n)

    def now_ns(self) -> int:
        return self.clock.now_ns()


def _registry() -> NodeRegistry:
    registry = builtin_registry()

    @action(name="FlakyReach")
    class FlakyReach(Leaf):
        def setup(self, **kwargs: Any) -> None:
            self.attempts = 0

        def initialise(self) -> None:
            self.attempts += 1
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            if self.ticks < 2:
                return Status.RUNNING
            return self.fail("UNREACHABLE", "out of reach") if self.attempts <= 2 else Status.SUCCESS

    @action(name="Recover")
    class Recover(Leaf):
        def initialise(self) -> None:
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            return Status.SUCCESS if self.ticks >= 2 else Status.RUNNING

    registry.register(FlakyReach)
    registry.register(Recover)
    return registry


def test_replay_counts_retries_and_failures_per_leaf_of_a_real_tree(tmp_path: Path) -> None:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, _registry(), clock=clock)
    for node in tree.nodes():
        node.setup()
    path = tmp_path / "run.mcap"
    recorder = RunRecorder(path, metadata={"seed": "0"})
    recorder.write_tree_structure(0, tree_structure(tree.root))
    outcome = TreeRunner(tree, Stepper(clock), steps_per_tick=1, recorder=recorder).run(max_ticks=50)
    recorder.close()
    assert outcome.status == "SUCCESS"
    assert outcome.retries == {"FlakyReach::3": 2}

    run = open_log(path)
    kinds = {info.name: (info.kind, info.is_leaf) for info in run.nodes.values()}
    assert kinds["FlakyReach"] == (NodeKind.ACTION.value, True)
    assert kinds["Recover"] == (NodeKind.ACTION.value, True)
    assert kinds["Fallback"] == (NodeKind.CONTROL.value, False)
    info = summary(run)
    # three attempts of FlakyReach, two failed, each followed by a retry; Recover ran twice, never retried;
    # ForceFailure failed on its own (its child succeeded), so it is reported, as a decorator, not a leaf, and
    # counted apart: false by design (keyed by each node's path, its one name: BT.CPP's fullPath, "name::uid"
    # for a node without a name)
    assert info["failures_per_leaf"] == {"FlakyReach::3": 2}
    assert info["false_by_design_per_leaf"] == {"ForceFailure::4": 2}
    assert info["retries_per_leaf"] == {"FlakyReach::3": 2}
