"""Control nodes, tick by tick, as BT.CPP 4.x's src/controls/*.cpp behave."""

from __future__ import annotations

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
    # tick 3: ok FAILURE -> Move is halted (terminate(INVALID)) -> FAILURE
    assert h.tick() == F
    assert h["Move"].terminated == ["INVALID"] and h.state("Move") == "IDLE"


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
