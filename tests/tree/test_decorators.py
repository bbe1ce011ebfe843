"""Decorators and built-in leaves, tick by tick, as BT.CPP 4.x's decorators/*.h behave."""

from __future__ import annotations

import pytest

from bt_grasp.tree.node import WAKE_UP_LIMIT

from .harness import F, Harness, R, S


@pytest.mark.parametrize(
    ("decorator", "child", "expected"),
    [
        ("Inverter", S, F),
        ("Inverter", F, S),
        ("Inverter", R, R),
        ("ForceSuccess", F, S),
        ("ForceSuccess", R, R),
        ("ForceFailure", S, F),
        ("ForceFailure", R, R),
    ],
)
def test_status_rewriting_decorators(decorator: str, child: str, expected: str) -> None:
    h = Harness(f'<{decorator}><Stub name="A"/></{decorator}>')
    h["A"].returns(child)
    assert h.tick() == expected


def test_retry_loops_within_one_tick_while_child_fails_synchronously() -> None:
    h = Harness('<RetryUntilSuccessful num_attempts="3"><Stub name="A"/></RetryUntilSuccessful>')
    h["A"].returns(F, F, S)
    # tick 1: A FAILURE, FAILURE, SUCCESS, all in the same tick -> SUCCESS
    assert h.tick() == S and h["A"].ticks == 3 and h["A"].initialised == 3


def test_retry_gives_up_after_num_attempts_and_resumes_running_child() -> None:
    h = Harness('<RetryUntilSuccessful num_attempts="2"><Stub name="A"/></RetryUntilSuccessful>')
    h["A"].returns(F, F)
    # tick 1: two synchronous failures -> FAILURE
    assert h.tick() == F and h["A"].ticks == 2
    h["A"].returns(F, R, S)
    # tick 2: FAILURE then RUNNING -> RUNNING; tick 3: SUCCESS (the count survived the RUNNING tick)
    assert h.tick() == R and h.tick() == S


def test_retry_forever_over_a_synchronous_failure_yields_each_period_not_a_hang() -> None:
    h = Harness('<RetryUntilSuccessful num_attempts="-1"><Stub name="A"/></RetryUntilSuccessful>')
    h["A"].returns(F)
    # BT.CPP's tickOnce() would re-run the root until something outside ends it; bt_grasp caps the re-runs
    # of one period at WAKE_UP_LIMIT and goes on in the next (RUNNING, no error)
    assert h.tick() == R and h["A"].ticks == WAKE_UP_LIMIT
    assert h.tree.root.bt_wake_up.requester == "RetryUntilSuccessful 'RetryUntilSuccessful::1'"
    h["A"].returns(S)
    # tick 2: the next attempt succeeds -> SUCCESS
    assert h.tick() == S and h["A"].ticks == WAKE_UP_LIMIT + 1


def test_repeat_loops_within_one_tick_and_fails_on_child_failure() -> None:
    h = Harness('<Repeat num_cycles="3"><Stub name="A"/></Repeat>')
    # tick 1: A SUCCESS x3 in one tick -> SUCCESS
    assert h.tick() == S and h["A"].ticks == 3
    h["A"].returns(S, R, F)
    # tick 2: SUCCESS, RUNNING -> RUNNING; tick 3: FAILURE -> FAILURE
    assert h.tick() == R and h.tick() == F


def test_keep_running_until_failure_returns_running_after_success() -> None:
    h = Harness('<KeepRunningUntilFailure><Stub name="A"/></KeepRunningUntilFailure>')
    h["A"].returns(S, S, F)
    # tick 1: SUCCESS -> RUNNING; tick 2: SUCCESS -> RUNNING; tick 3: FAILURE -> FAILURE
    assert [h.tick(), h.tick(), h.tick()] == [R, R, F]
    assert h["A"].initialised == 3


def test_timeout_halts_running_child_after_simulated_time() -> None:
    h = Harness('<Timeout msec="100"><Stub name="Move"/></Timeout>')
    h["Move"].returns(R)
    # t=0: RUNNING; t=60ms: RUNNING; t=120ms: 100ms passed -> Move halted -> FAILURE
    assert h.tick() == R
    h.clock.advance_s(0.06)
    assert h.tick() == R
    h.clock.advance_s(0.06)
    assert h.tick() == F
    assert h["Move"].terminated == ["IDLE"] and h["Move"].ticks == 2
    # the next activation starts a new timer
    assert h.tick() == R


def test_timeout_passes_child_result_before_deadline() -> None:
    h = Harness('<Timeout msec="100"><Stub name="A"/></Timeout>')
    h["A"].returns(R, S)
    assert h.tick() == R
    h.clock.advance_s(0.05)
    assert h.tick() == S


def test_delay_waits_then_ticks_child() -> None:
    h = Harness('<Delay delay_msec="50"><Stub name="A"/></Delay>')
    # t=0: RUNNING, child untouched; t=30ms: RUNNING; t=60ms: child ticked -> SUCCESS
    assert h.tick() == R and h["A"].ticks == 0
    h.clock.advance_s(0.03)
    assert h.tick() == R and h["A"].ticks == 0
    h.clock.advance_s(0.03)
    assert h.tick() == S and h["A"].ticks == 1


def test_sleep_reads_simulated_clock() -> None:
    h = Harness('<Sleep msec="20"/>')
    # t=0 RUNNING, t=10ms RUNNING, t=20ms SUCCESS
    statuses = []
    for _ in range(3):
        statuses.append(h.tick())
        h.clock.advance_s(0.01)
    assert statuses == [R, R, S]


def test_run_once_skips_afterwards_or_repeats_status() -> None:
    h = Harness('<Sequence><RunOnce><Stub name="A"/></RunOnce><Stub name="B"/></Sequence>')
    assert h.tick() == S and h.tick() == S
    # the second time RunOnce is SKIPPED: A is not ticked again
    assert h["A"].ticks == 1 and h["B"].ticks == 2
    h2 = Harness('<RunOnce then_skip="false"><AlwaysFailure/></RunOnce>')
    assert [h2.tick(), h2.tick()] == [F, F]


def test_precondition_if_else() -> None:
    xml = """<Sequence><Script code="A:=1; B:=1; C:=3"/>
             <Precondition if="A==B" else="FAILURE"><Stub name="X"/></Precondition>
             <Precondition if="A==C" else="SUCCESS"><Stub name="Y"/></Precondition></Sequence>"""
    h = Harness(xml)
    assert h.tick() == S and h["X"].ticks == 1 and h["Y"].ticks == 0


def test_precondition_is_checked_only_before_the_child_runs() -> None:
    h = Harness('<Sequence><Script code="go := true"/><Precondition if="go"><Stub name="X"/></Precondition></Sequence>')
    h["X"].returns(R, S)
    assert h.tick() == R
    h.tree.root_blackboard.set("go", False)
    # the child is already running: the condition is not re-evaluated
    assert h.tick() == S


def test_set_blackboard_and_scripts() -> None:
    xml = """<Sequence>
      <SetBlackboard value="42" output_key="answer"/>
      <SetBlackboard value="{answer}" output_key="copy"/>
      <Script code="msg := 'answer=' .. answer"/>
      <ScriptCondition code="answer == 42 &amp;&amp; copy == '42'"/>
    </Sequence>"""
    h = Harness(xml)
    assert h.tick() == S
    # like BT.CPP, SetBlackboard stores the literal text; scripts convert it where a number is needed
    assert h.bb == {"answer": "42", "copy": "42", "msg": "answer=42"}


def test_script_condition_false_fails() -> None:
    h = Harness('<ScriptCondition code="1 &gt; 2"/>')
    assert h.tick() == F


def test_failure_is_reads_the_reason_a_leaf_reported() -> None:
    xml = """<Fallback>
      <Stub name="Perceive"/>
      <Sequence><FailureIs reason="NO_DETECTION"/><Script code="recovered := true"/></Sequence>
    </Fallback>"""
    h = Harness(xml)

    def failing_update() -> object:
        return h.node("Perceive").fail("NO_DETECTION", "no object in view")  # type: ignore[attr-defined]

    h.node("Perceive").update = failing_update  # type: ignore[method-assign]
    assert h.tick() == S
    assert h.bb["recovered"] == 1.0  # FailureIs read failure_reason = NO_DETECTION (and failed_leaf = Perceive)
    assert "failure_reason" not in h.bb and "failed_leaf" not in h.bb  # cleared: the tree succeeded
    assert h.node("Perceive").failure_reason == "NO_DETECTION"  # type: ignore[attr-defined]


def test_skip_unless_updated_ticks_the_child_once_per_write() -> None:
    xml = (
        '<Sequence><Script code="x := 1"/><SkipUnlessUpdated entry="x"><Stub name="A"/></SkipUnlessUpdated></Sequence>'
    )
    h = Harness(f"<KeepRunningUntilFailure>{xml}</KeepRunningUntilFailure>")
    # tick 1: x written -> A ticked; tick 2: x written again -> A ticked again
    assert h.tick() == R and h.tick() == R and h["A"].ticks == 2
    h2 = Harness(
        '<Sequence><Script code="x := 1"/><SkipUnlessUpdated entry="x"><Stub name="A"/></SkipUnlessUpdated>'
        '<SkipUnlessUpdated name="second" entry="x"><Stub name="B"/></SkipUnlessUpdated></Sequence>'
    )
    h2["A"].returns(R, S)
    # tick 1: A RUNNING; tick 2: A resumed although x was not written again -> SUCCESS; B saw the write too
    assert h2.tick() == R and h2.tick() == S and h2["A"].ticks == 2 and h2["B"].ticks == 1


def test_wait_value_update_is_running_until_the_entry_is_written() -> None:
    h = Harness('<WaitValueUpdate entry="{x}"><Stub name="A"/></WaitValueUpdate>')
    # ticks 1-2: x never written -> RUNNING, A not ticked
    assert h.tick() == R and h.tick() == R and h["A"].ticks == 0
    h.tree.root_blackboard.set("x", 3)
    # tick 3: x written -> A SUCCESS -> SUCCESS
    assert h.tick() == S and h["A"].ticks == 1


def test_repeat_yields_after_each_synchronous_cycle() -> None:
    h = Harness(
        '<ReactiveSequence><Check name="ok"/><Repeat num_cycles="3"><Stub name="A"/></Repeat></ReactiveSequence>'
    )
    # one control period: three root executions (BT.CPP's wake-up), so the condition is checked 3 times
    assert h.tick() == S and h.tree.runs == 3 and h["ok"].ticks == 3 and h["A"].ticks == 3


def test_precondition_checks_again_after_a_halt() -> None:
    # a deliberate deviation: BT.CPP 4.10 keeps "child running" through a halt and would resume unchecked
    xml = (
        '<ReactiveSequence><Check name="ok"/>'
        '<Precondition if="go == 1"><Stub name="X"/></Precondition></ReactiveSequence>'
    )
    h = Harness(xml)
    h.tree.root_blackboard.set("go", 1)
    h["ok"].returns(S, F, S)
    h["X"].returns(R)
    # tick 1: go == 1 -> X RUNNING; tick 2: ok FAILURE -> the Precondition is halted (X halted)
    assert h.tick() == R and h.tick() == F and h["X"].halted == 1
    h.tree.root_blackboard.set("go", 0)
    # tick 3: the condition is checked again (false) -> else (FAILURE); X is not resumed
    assert h.tick() == F and h["X"].ticks == 1
