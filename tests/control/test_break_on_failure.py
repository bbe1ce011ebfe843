"""`--break fail` stops where `replay --failures` sees a failure (issue 43, finding 7).

- ``fail`` pauses after a leaf FAILURE unless the failure is false by design (a condition asked by a Fallback, or
  one answering "no" without a reason), by the one rule ``replay --failures`` applies to a log; ``fail:all`` keeps
  the old behaviour (every leaf FAILURE).
- The "last failure" panel shows the failure that matters, with its reason, not the ``FailureIs`` a Fallback
  asked right after it.
- When the run ends, the view's tick is the run's last tick (the summary's), not the one before.

The stand-in tree, tick by tick::

    Sequence main
      Fallback holding_or_grab
        Held                      Condition: FAILURE GRASP_EMPTY (by design: asked by a Fallback), tick 1
        RetryUntilSuccessful(2)
          Fallback attempt_or_recover
            Grab                  tick 1 RUNNING; tick 2 FAILURE SLIPPED; tick 2 again (the retry) RUNNING;
                                  tick 3 SUCCESS
            ForceFailure
              Asked               Condition: FAILURE with no reason (by design), right after Grab's in tick 2,
                                  as lib/pick.xml's RecoverPick asks its FailureIs conditions
      Fallback then
        Held name=still_held      by design again, in tick 3 (the last)
        AlwaysSuccess
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bt_grasp.clock import ManualClock
from bt_grasp.control import Controller, Resume, RunState, Source, parse_breakpoint
from bt_grasp.nodes import Leaf, Status, action, condition
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string
from bt_grasp.tree.runner import TreeRunner
from tests.control.stand_ins import Stepper

REPO = Path(__file__).resolve().parents[2]

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence name="main">
      <Fallback name="holding_or_grab">
        <Held/>
        <RetryUntilSuccessful num_attempts="2">
          <Fallback name="attempt_or_recover">
            <Grab/>
            <ForceFailure><Asked/></ForceFailure>
          </Fallback>
        </RetryUntilSuccessful>
      </Fallback>
      <Fallback name="then">
        <Held name="still_held"/>
        <AlwaysSuccess/>
      </Fallback>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _tree() -> tuple[LoadedTree, Stepper]:
    registry = builtin_registry()

    @condition()
    class Held(Leaf):
        def update(self) -> Status:
            return self.fail("GRASP_EMPTY", "nothing between the fingers")

    @action()
    class Grab(Leaf):
        def setup(self, **kwargs: Any) -> None:
            self.ticks = 0

        def update(self) -> Status:
            self.ticks += 1
            if self.ticks == 2:
                return self.fail("SLIPPED", "the object slipped out")
            return Status.SUCCESS if self.ticks >= 4 else Status.RUNNING

    @condition()
    class Asked(Leaf):
        def update(self) -> Status:
            return Status.FAILURE

    registry.register(Held)
    registry.register(Grab)
    registry.register(Asked)
    clock = ManualClock()
    tree = load_tree_from_string(TREE, registry, clock=clock)
    for node in tree.nodes():
        node.setup()
    return tree, Stepper(clock)


def _run(spec: str) -> tuple[list[RunState], Controller, int]:
    seen: list[RunState] = []
    control: Controller

    def idle(state: RunState) -> None:
        seen.append(state)
        control.send(Resume(), Source.TERMINAL)

    control = Controller([parse_breakpoint(spec)], idle=idle)
    tree, stepper = _tree()
    control.attach(tree, stepper.now_ns)
    outcome = TreeRunner(tree, stepper, steps_per_tick=1, gate=control).run(20)
    assert outcome.status == "SUCCESS" and outcome.ticks == 3
    return seen, control, outcome.ticks


def test_break_fail_skips_the_failures_false_by_design() -> None:
    seen, _, _ = _run("fail")
    assert [s.tick for s in seen] == [2]  # not tick 1 (Held, asked by a Fallback), not tick 3 (still_held)
    assert "SLIPPED" in seen[0].pause_reason and "Grab" in seen[0].pause_reason


def test_break_fail_all_stops_at_every_leaf_failure() -> None:
    seen, _, _ = _run("fail:all")
    assert [s.tick for s in seen] == [1, 2]  # tick 3 ends the run: no pause after it
    assert "false by design" in seen[0].pause_reason and "GRASP_EMPTY" in seen[0].pause_reason
    assert parse_breakpoint("fail:all").spec == "fail:all"


def test_the_last_failure_panel_shows_the_failure_that_matters_with_its_reason() -> None:
    seen, control, _ = _run("fail")
    end = control.state()
    failure = seen[0].last_failure
    assert failure is not None and (failure.tick, failure.leaf, failure.reason) == (2, "Grab", "SLIPPED")
    # Asked failed (by design, no reason) after it in the same tick: the panel keeps the failure that matters
    assert end.last_failure is not None and end.last_failure.leaf == "Grab"
    from bt_grasp.cli.interactive_ui import failure_text

    text = failure_text(end)
    assert "SLIPPED" in text and "Grab" in text and "the object slipped out" in text


def test_the_views_last_tick_is_the_runs() -> None:
    _, control, ticks = _run("fail")
    control.finish(ticks)  # as the episode does when its run ends (the tick loop consults no gate after it)
    end = control.state()
    assert end.finished and end.tick == ticks == 3


def test_the_rule_is_replays_one_function() -> None:
    """The tick loop (the live failure line, the causal chain, breakpoints) and `replay --failures` call one
    function, not two copies of a rule."""
    import bt_grasp.recording.replay as replay
    import bt_grasp.tree.runner as runner
    from bt_grasp.tree.failure_kinds import false_by_design

    assert runner.false_by_design is false_by_design and replay.false_by_design is false_by_design
    assert not hasattr(runner, "_by_design") and not hasattr(replay, "_by_design")


@pytest.mark.sim
def test_break_fail_does_not_stop_at_the_library_subtrees_first_condition(tmp_path: Path) -> None:
    """The issue's case: every tree using lib/pick.xml asks IsGrasped first (GRASP_EMPTY, false by design in its
    Fallback); `--break fail` stopped there at tick 1. The view's last tick is the result's."""
    from bt_grasp.episode import Episode, EpisodeRequest

    seen: list[RunState] = []
    control: Controller

    def idle(state: RunState) -> None:
        seen.append(state)
        control.send(Resume(), Source.TERMINAL)

    control = Controller([parse_breakpoint("fail")], idle=idle)
    episode = Episode(EpisodeRequest(tree=REPO / "trees/clear_table.xml", scene=REPO / "scenes/clear_table.yaml",
                                     seed=0, max_ticks=60))
    result = episode.run(controller=control)
    assert [s.pause_reason for s in seen] == []
    assert control.state().tick == result.ticks == 60
