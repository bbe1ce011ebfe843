"""Control nodes, tick by tick, as BT.CPP 4.x's src/controls/*.cpp behave."""

from __future__ import annotations

import pytest

from bt_grasp.tree.exceptions import TreeRuntimeError

from .harness import F, Harness, R, S


def test_sequence_resumes_running_child_and_restarts_after_failure() -> None:
    h = Harness('<Sequence><Stub name="A"/><Stub name="B"/><Stub name="C"/></Sequence>')
    h["B"].returns(R, S)
    h["C"].returns(F, S)
    # tick 1: A SUCCESS, B RUNNING -> RUNNING
    assert h.tick() == R and h["A"].ticks == 1 and h.state("B") == R
    # tick 2: A is not ticked again; B SUCCESS, C FAILURE -> FAILURE, children reset
    assert h.tick() == F
    assert h["A"].ticks == 1 and h["B"].ticks == 2 and h["C"].ticks == 1
    assert h.state("A") == "IDLE" and h.state("C") == "IDLE"
    # tick 3: starts from A again; all succeed -> SUCCESS
    assert h.tick() == S and h["A"].ticks == 2 and h["C"].ticks == 2


def test_sequence_with_memory_resumes_at_failed_child() -> None:
    h = Harness('<SequenceWithMemory><Stub name="A"/><Stub name="B"/></SequenceWithMemory>')
    h["B"].returns(F, S)
    # tick 1: A SUCCESS, B FAILURE -> FAILURE (A keeps its place)
    assert h.tick() == F
    # tick 2: A not ticked again, B SUCCESS -> SUCCESS
    assert h.tick() == S
    assert h["A"].ticks == 1 and h["B"].ticks == 2


def test_reactive_sequence_halts_running_child_when_condition_fails() -> None:
    h = Harness('<ReactiveSequence><Check name="ok"/><Stub name="Move"/></ReactiveSequence>')
    h["ok"].returns(S, S, F)
    h["Move"].returns(R)
    # tick 1: ok SUCCESS, Move RUNNING -> RUNNING
    assert h.tick() == R
    # tick 2: ok is re-checked (SUCCESS), Move still RUNNING
    assert h.tick() == R and h["ok"].ticks == 2 and h["Move"].initialised == 1
    # tick 3: ok FAILURE -> Move is halted (terminate(IDLE)) -> FAILURE
    assert h.tick() == F
    assert h["Move"].terminated == ["IDLE"] and h.state("Move") == "IDLE"


def test_reactive_sequence_halts_other_children_when_one_runs() -> None:
    h = Harness('<ReactiveSequence><Stub name="A"/><Stub name="B"/><Stub name="C"/></ReactiveSequence>')
    h["B"].returns(R, S)
    h["C"].returns(R)
    # tick 1: A SUCCESS, B RUNNING -> RUNNING, A reset to IDLE
    assert h.tick() == R and h.state("A") == "IDLE" and h.state("B") == R
    # tick 2: A SUCCESS, B SUCCESS, C RUNNING: B goes back to IDLE
    assert h.tick() == R and h.state("B") == "IDLE" and h.state("C") == R


def test_fallback_and_reactive_fallback() -> None:
    h = Harness('<Fallback><Stub name="A"/><Stub name="B"/></Fallback>')
    h["A"].returns(F)
    h["B"].returns(R, S)
    # tick 1: A FAILURE, B RUNNING -> RUNNING; tick 2: B resumed (A not re-ticked) -> SUCCESS
    assert h.tick() == R and h.tick() == S
    assert h["A"].ticks == 1
    h2 = Harness('<ReactiveFallback><Check name="done"/><Stub name="Work"/></ReactiveFallback>')
    h2["done"].returns(F, S)
    h2["Work"].returns(R)
    # tick 1: done FAILURE, Work RUNNING; tick 2: done SUCCESS -> Work halted -> SUCCESS
    assert h2.tick() == R and h2.tick() == S
    assert h2["Work"].halted == 1


def test_fallback_all_fail() -> None:
    h = Harness("<Fallback><AlwaysFailure/><AlwaysFailure/></Fallback>")
    assert h.tick() == F


def test_parallel_thresholds() -> None:
    h = Harness(
        '<Parallel success_count="2" failure_count="2"><Stub name="A"/><Stub name="B"/><Stub name="C"/></Parallel>'
    )
    h["A"].returns(R, S)
    h["B"].returns(R, R, S)
    h["C"].returns(F)
    # tick 1: A RUNNING, B RUNNING, C FAILURE (1 failure) -> RUNNING
    assert h.tick() == R
    # tick 2: A SUCCESS (1), B RUNNING; C is done and not re-ticked -> RUNNING
    assert h.tick() == R and h["C"].ticks == 1
    # tick 3: B SUCCESS -> 2 successes -> SUCCESS; all children reset
    assert h.tick() == S and h["A"].ticks == 2


def test_parallel_default_all_must_succeed_and_one_failure_fails() -> None:
    h = Harness('<Parallel><Stub name="A"/><Stub name="B"/></Parallel>')
    h["A"].returns(S)
    h["B"].returns(R, F)
    # tick 1: A SUCCESS, B RUNNING -> RUNNING; tick 2: B FAILURE -> failure_count=1 reached -> FAILURE
    assert h.tick() == R and h.tick() == F


def test_parallel_halts_running_children_when_it_finishes() -> None:
    h = Harness('<Parallel success_count="1"><Stub name="A"/><Stub name="B"/></Parallel>')
    h["A"].returns(S)
    h["B"].returns(R)
    # tick 1: A SUCCESS -> threshold 1 reached before B is ticked -> SUCCESS
    assert h.tick() == S and h["B"].ticks == 0
    h["A"].returns(R, S)
    # tick 2: A RUNNING, B RUNNING; tick 3: A SUCCESS -> SUCCESS and the RUNNING B is halted
    assert h.tick() == R and h.tick() == S and h["B"].halted == 1


def test_if_then_else_checks_condition_once() -> None:
    h = Harness('<IfThenElse><Check name="c"/><Stub name="then"/><Stub name="else"/></IfThenElse>')
    h["c"].returns(S, F)
    h["then"].returns(R, S)
    # tick 1: c SUCCESS -> then RUNNING; tick 2: c NOT re-checked, then SUCCESS -> SUCCESS
    assert h.tick() == R and h.tick() == S and h["c"].ticks == 1
    # tick 3: c FAILURE -> else SUCCESS
    assert h.tick() == S and h["else"].ticks == 1


def test_if_then_else_two_children_fails_when_condition_fails() -> None:
    h = Harness('<IfThenElse><AlwaysFailure/><Stub name="then"/></IfThenElse>')
    assert h.tick() == F and h["then"].ticks == 0


def test_while_do_else_rechecks_and_halts_the_other_branch() -> None:
    h = Harness('<WhileDoElse><Check name="c"/><Stub name="do"/><Stub name="else"/></WhileDoElse>')
    h["c"].returns(S, S, F)
    h["do"].returns(R)
    h["else"].returns(R)
    # tick 1-2: c SUCCESS -> do RUNNING; tick 3: c FAILURE -> do halted, else RUNNING
    assert [h.tick(), h.tick(), h.tick()] == [R, R, R]
    assert h["do"].halted == 1 and h.state("else") == R and h["c"].ticks == 3


def test_async_sequence_yields_after_each_synchronous_child() -> None:
    h = Harness(
        '<ReactiveSequence><Check name="ok"/><AsyncSequence><Stub name="A"/><Stub name="B"/></AsyncSequence>'
        "</ReactiveSequence>"
    )
    # tick 1, run 1: ok SUCCESS, A SUCCESS -> AsyncSequence RUNNING + wake-up
    #         run 2: ok SUCCESS, B SUCCESS -> SUCCESS (one control period, two root executions)
    assert h.tick() == S and h.tree.runs == 2 and h["ok"].ticks == 2


def test_async_fallback_yields_after_each_synchronous_failure() -> None:
    h = Harness('<AsyncFallback><Stub name="A"/><Stub name="B"/></AsyncFallback>')
    h["A"].returns(F)
    # run 1: A FAILURE -> RUNNING + wake-up; run 2: B SUCCESS -> SUCCESS
    assert h.tick() == S and h.tree.runs == 2


def test_sequence_with_memory_yields_after_a_synchronous_child() -> None:
    h = Harness('<SequenceWithMemory><Stub name="A"/><Stub name="B"/><Stub name="C"/></SequenceWithMemory>')
    # runs 1-3 within one tick: A, then B, then C -> SUCCESS
    assert h.tick() == S and h.tree.runs == 3


def test_parallel_all_waits_for_every_child_and_counts_failures() -> None:
    h = Harness('<ParallelAll max_failures="1"><Stub name="A"/><Stub name="B"/></ParallelAll>')
    h["A"].returns(F)
    h["B"].returns(R, S)
    # tick 1: A FAILURE (not re-ticked later), B RUNNING -> RUNNING (a failure does not stop B)
    assert h.tick() == R and h["B"].halted == 0
    # tick 2: B SUCCESS; 1 failure >= max_failures -> FAILURE
    assert h.tick() == F and h["A"].ticks == 1


def test_parallel_all_succeeds_below_max_failures() -> None:
    h = Harness('<ParallelAll max_failures="2"><Stub name="A"/><Stub name="B"/></ParallelAll>')
    h["A"].returns(F)
    # tick 1: one failure < 2 -> SUCCESS
    assert h.tick() == S


def test_try_catch_runs_catch_then_fails() -> None:
    h = Harness('<TryCatch><Stub name="A"/><Stub name="B"/><Stub name="Catch"/></TryCatch>')
    h["B"].returns(F)
    h["Catch"].returns(R, S)
    # tick 1: A SUCCESS, B FAILURE -> catch RUNNING -> RUNNING
    assert h.tick() == R
    # tick 2: catch SUCCESS -> the node FAILS; the try block is not re-run
    assert h.tick() == F and h["A"].ticks == 1 and h["B"].ticks == 1


def test_try_catch_succeeds_without_catch() -> None:
    h = Harness('<TryCatch><Stub name="A"/><Stub name="Catch"/></TryCatch>')
    # tick 1: A SUCCESS -> SUCCESS, the catch child never ticks
    assert h.tick() == S and h["Catch"].ticks == 0


def test_try_catch_on_halt_runs_catch_once() -> None:
    xml = (
        '<ReactiveSequence><Check name="ok"/>'
        '<TryCatch catch_on_halt="true"><Stub name="A"/><Stub name="Catch"/></TryCatch></ReactiveSequence>'
    )
    h = Harness(xml)
    h["ok"].returns(S, F)
    h["A"].returns(R)
    # tick 1: A RUNNING -> RUNNING
    assert h.tick() == R
    # tick 2: ok FAILURE -> TryCatch halted: A halted, Catch ticked once -> FAILURE
    assert h.tick() == F and h["A"].halted == 1 and h["Catch"].ticks == 1


def test_switch_picks_the_matching_case_and_halts_the_old_one() -> None:
    xml = (
        '<ReactiveSequence><Script code="mode := m"/><Switch2 variable="{mode}" case_1="a" case_2="2">'
        '<Stub name="A"/><Stub name="Two"/><Stub name="Other"/></Switch2></ReactiveSequence>'
    )
    h = Harness(xml)
    h.tree.root_blackboard.set("m", "a")
    h["A"].returns(R)
    # tick 1: mode 'a' -> case 1 (A) RUNNING
    assert h.tick() == R and h["A"].ticks == 1
    # tick 2: mode 2 (an integer matches the case text "2") -> A halted, Two SUCCESS
    h.tree.root_blackboard.set("m", "2")
    assert h.tick() == S and h["A"].halted == 1 and h["Two"].ticks == 1


def test_switch_default_is_the_last_child() -> None:
    children = "".join(f'<Stub name="{n}"/>' for n in "ABCD")
    h = Harness(f'<Switch3 variable="x" case_1="1" case_2="2" case_3="3">{children}</Switch3>')
    # tick 1: "x" matches no case -> the default (D)
    assert h.tick() == S and h["D"].ticks == 1 and h["A"].ticks == 0


@pytest.mark.parametrize("control", ["IfThenElse", "WhileDoElse"])
def test_a_skipped_condition_is_a_tick_error(control: str) -> None:
    # BT.CPP throws a logic error here too; bt_grasp names the node
    h = Harness(f'<{control}><Check name="c" _skipIf="true"/><Stub name="a"/><Stub name="b"/></{control}>')
    with pytest.raises(TreeRuntimeError, match="the condition \\(first child\\) was skipped"):
        h.tick()
