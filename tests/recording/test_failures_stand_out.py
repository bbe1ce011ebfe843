"""Failures that stand out (issue 24): a real tree run by the real runner, recorded and read back.

Replay's failures view separates the failure that decided the outcome and the ones recovered from the
conditions that were false by design (a ``FailureIs`` asked by a Fallback, ``ForceFailure``); the runner says
each real failure as it happens (the CLI's live line) and ends with the causal chain (what followed each).
On the code before, every FAILURE was one undifferentiated list, nothing was said live, and the summary had
no chain.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_grasp.clock import ManualClock
from bt_grasp.nodes import Leaf, Status, action
from bt_grasp.recording import replay
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.render import failures_table
from bt_grasp.recording.writer import RunRecorder
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.introspect import tree_structure
from bt_grasp.tree.loader import load_tree_from_string
from bt_grasp.tree.registry import NodeRegistry
from bt_grasp.tree.runner import FailureEvent, RunOutcome, TreeRunner

# Reach fails twice (UNREACHABLE) and succeeds on its third attempt; after each failure the Fallback asks
# FailureIs (false: the reason is not PLAN_FAILED) then runs Recover, and ForceFailure makes the attempt fail
# so the retry starts Reach again. Then Doomed fails (GRASP_EMPTY) and the root fails with it.
TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <Sequence name="main">
      <RetryUntilSuccessful num_attempts="5">
        <Fallback name="attempt_or_recover">
          <Reach name="reach"/>
          <ForceFailure name="recover_then_retry">
            <Fallback name="by_reason">
              <FailureIs name="plan_failed" reason="PLAN_FAILED"/>
              <Recover name="recover"/>
            </Fallback>
          </ForceFailure>
        </Fallback>
      </RetryUntilSuccessful>
      <Doomed name="doomed"/>
    </Sequence>
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

    @action(name="Reach")
    class Reach(Leaf):
        def setup(self, **kwargs: Any) -> None:
            self.attempts = 0

        def initialise(self) -> None:
            self.attempts += 1
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            if self.ticks < 2:
                return Status.RUNNING
            return self.fail("IK_UNREACHABLE", "out of reach") if self.attempts <= 2 else Status.SUCCESS

    @action(name="Recover")
    class Recover(Leaf):  # two ticks, so each failure and retry is on a tick of its own in the log
        def initialise(self) -> None:
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            return Status.SUCCESS if self.ticks >= 2 else Status.RUNNING

    @action(name="Doomed")
    class Doomed(Leaf):
        def update(self) -> Status:
            return self.fail("GRASP_EMPTY", "nothing between the fingers")

    registry.register(Reach)
    registry.register(Recover)
    registry.register(Doomed)
    return registry


def _run(tmp_path: Path, live: bool = True) -> tuple[RunOutcome, list[FailureEvent], Path]:
    clock = ManualClock()
    tree = load_tree_from_string(TREE, _registry(), clock=clock)
    for node in tree.nodes():
        node.setup()
    path = tmp_path / "run.mcap"
    seen: list[FailureEvent] = []
    with RunRecorder(path, metadata={"seed": "0"}, handle_signals=False) as recorder:
        recorder.write_tree_structure(0, tree_structure(tree.root))
        told: dict[str, Any] = {"on_failure": seen.append} if live else {}
        outcome = TreeRunner(tree, Stepper(clock), steps_per_tick=1, recorder=recorder, **told).run(max_ticks=50)
        last = outcome.last_failure
        recorder.write_result(clock.now_ns(), {"success": False, "reason": last.reason if last else None,
                                               "failed_leaf": last.leaf if last else None,
                                               "failed_path": last.path if last else None})
    return outcome, seen, path


def test_replay_separates_the_deciding_failure_from_conditions_false_by_design(tmp_path: Path) -> None:
    outcome, _, path = _run(tmp_path, live=False)
    assert outcome.status == "FAILURE"
    reports = replay.failures(open_log(path))
    kinds = [(f.path, f.reason, f.kind) for f in reports]
    assert kinds == [
        ("reach", "IK_UNREACHABLE", replay.FailureKind.RECOVERED),
        ("plan_failed", None, replay.FailureKind.BY_DESIGN),
        ("recover_then_retry", None, replay.FailureKind.BY_DESIGN),
        ("reach", "IK_UNREACHABLE", replay.FailureKind.RECOVERED),
        ("plan_failed", None, replay.FailureKind.BY_DESIGN),
        ("recover_then_retry", None, replay.FailureKind.BY_DESIGN),
        ("doomed", "GRASP_EMPTY", replay.FailureKind.OUTCOME),
    ], kinds
    assert [f.path for f in replay.failure_chain(open_log(path))] == ["reach", "reach", "doomed"]
    # the view says it: the deciding one marked, the others apart under "false by design"
    from rich.console import Console

    console = Console(width=160, record=True)
    console.print(failures_table(reports))
    text = console.export_text()
    real, _, by_design = text.partition("false by design: 4")
    assert by_design, text
    assert "decided the outcome  tick" in real and "doomed  GRASP_EMPTY" in real
    assert real.count("recovered  tick") == 2 and "plan_failed" not in real
    assert "plan_failed" in by_design and "recover_then_retry" in by_design and "doomed" not in by_design


def test_each_real_failure_is_told_as_it_happens_and_the_chain_says_what_followed(tmp_path: Path) -> None:
    outcome, seen, _ = _run(tmp_path)
    # one live line per real failure, none for the condition that answered "no" or the ForceFailure
    assert [(e.path, e.reason) for e in seen] == [
        ("reach", "IK_UNREACHABLE"), ("reach", "IK_UNREACHABLE"), ("doomed", "GRASP_EMPTY")]
    assert all(e.stamp_ns == (e.tick - 1) * 10_000_000 for e in seen)  # the tick's simulated time
    retried = [e.tick for e in seen[:2]]
    chain = [(e.path, e.followed) for e in outcome.chain]
    assert chain[2] == ("doomed", "the run ended (FAILURE)")
    for (path, followed), failed_at in zip(chain[:2], retried, strict=True):
        assert path == "reach" and followed.startswith("retried at tick ")
        assert int(followed.rsplit(" ", 1)[1]) > failed_at  # after its recovery ran


def test_the_run_summary_ends_with_the_chain_and_each_failure_gets_a_live_line() -> None:
    import io

    from rich.console import Console

    from bt_grasp.cli.run_cmd import failure_line, print_summary
    from bt_grasp.episode import EpisodeResult
    from bt_grasp.episode.instruments import PlanningStats
    from bt_grasp.episode.result import ChainStep, Judged
    from bt_grasp.scene.goals import PickGoal

    goal = PickGoal(kind="pick")
    chain = (ChainStep(12, 0.11, "PickObject::18/Perceive::27", "NO_FRAME", "retried at tick 31"),
             ChainStep(90, 0.89, "PickObject::18/Grasp::30", "GRASP_EMPTY", "the run ended (FAILURE)"))
    result = EpisodeResult(
        success=False, tree_status="FAILURE", reason="GRASP_EMPTY", failed_leaf="Grasp",
        failed_path="PickObject::18/Grasp::30", ticks=90, sim_time_s=0.9, wall_time_s=0.1, retries={}, seed=0,
        goal=goal, log=None, judged=Judged(goal=goal, success=False, failed_condition=None, conditions=()),
        planning=PlanningStats(calls=0, pose_calls=0, wall_s=0.0), failure_chain=chain)
    out = io.StringIO()
    print_summary(Console(file=out, width=200, color_system=None), result)
    lines = out.getvalue().rstrip().splitlines()
    assert "leaf: PickObject::18/Grasp::30" in out.getvalue()  # the path, as everywhere else
    assert lines[-3:] == [
        "  what failed, and what followed (oldest first):",
        "    tick 12 (0.11 s) PickObject::18/Perceive::27 NO_FRAME -> retried at tick 31",
        "    tick 90 (0.89 s) PickObject::18/Grasp::30 GRASP_EMPTY -> the run ended (FAILURE)"]
    assert result.to_json()["failure_chain"][0]["leaf_path"] == "PickObject::18/Perceive::27"

    live = io.StringIO()
    failure_line(Console(file=live, width=200, color_system=None))(
        FailureEvent(12, 110_000_000, "Perceive", "PickObject::18/Perceive::27", "NO_FRAME", "no frame"))
    assert live.getvalue() == "FAILED PickObject::18/Perceive::27: NO_FRAME at tick 12, t=0.11 s (no frame)\n"
