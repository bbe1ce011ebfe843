"""Pre- and post-condition attributes with BT.CPP's rules (src/tree_node.cpp)."""

from __future__ import annotations

from .harness import F, Harness, R, S


def test_skip_if_skips_and_sequence_continues() -> None:
    h = Harness('<Sequence><Script code="skip := true"/><Stub name="A" _skipIf="skip"/><Stub name="B"/></Sequence>')
    # A is SKIPPED (never ticked), the Sequence goes on to B -> SUCCESS
    assert h.tick() == S and h["A"].ticks == 0 and h["B"].ticks == 1
    node = h.node("A")
    assert node.bt_status_extra == "SKIPPED" and node.status.name == "INVALID"


def test_sequence_of_only_skipped_children_is_skipped() -> None:
    h = Harness(
        '<Sequence><Script code="s := true"/>'
        '<Sequence name="inner"><Stub name="A" _skipIf="s"/><Stub name="B" _skipIf="s"/></Sequence></Sequence>'
    )
    assert h.tick() == S
    assert h.node("inner").bt_status_extra == "SKIPPED"


def test_fallback_skips_skipped_children() -> None:
    h = Harness('<Fallback><AlwaysSuccess _skipIf="true"/><Stub name="B"/></Fallback>')
    assert h.tick() == S and h["B"].ticks == 1


def test_failure_if_and_success_if_replace_the_tick() -> None:
    h = Harness('<Sequence><Stub name="A" _failureIf="true"/></Sequence>')
    assert h.tick() == F and h["A"].ticks == 0
    h2 = Harness('<Stub name="A" _successIf="1 &lt; 2"/>')
    assert h2.tick() == S and h2["A"].ticks == 0


def test_failure_if_wins_over_success_if() -> None:
    h = Harness('<Stub name="A" _successIf="true" _failureIf="true"/>')
    assert h.tick() == F


def test_preconditions_are_checked_only_when_idle() -> None:
    h = Harness('<Sequence><Script code="stop := false"/><Stub name="A" _failureIf="stop"/></Sequence>')
    h["A"].returns(R, R, S)
    # tick 1: A RUNNING; stop turns true while A runs: _failureIf is not checked again
    assert h.tick() == R
    h.tree.root_blackboard.set("stop", True)
    assert h.tick() == R and h.tick() == S


def test_while_halts_running_node_when_it_turns_false() -> None:
    h = Harness(
        '<Sequence><Script code="go := true"/><Stub name="Move" _while="go" _onHalted="halted := true"/></Sequence>'
    )
    h["Move"].returns(R)
    # tick 1: go true -> Move RUNNING
    assert h.tick() == R
    h.tree.root_blackboard.set("go", False)
    # tick 2: _while false while RUNNING -> Move halted (terminate IDLE), SKIPPED -> the Sequence succeeds
    assert h.tick() == S
    assert h["Move"].terminated == ["IDLE"] and h.bb["halted"] == 1.0


def test_while_false_when_idle_skips() -> None:
    h = Harness('<Fallback><Stub name="A" _while="false"/><AlwaysFailure/></Fallback>')
    assert h.tick() == F and h["A"].ticks == 0


def test_post_conditions() -> None:
    xml = """<Sequence>
      <Script code="n := 0"/>
      <Stub name="A" _onSuccess="ok := true" _post="n += 1"/>
      <ForceSuccess><Stub name="B" _onFailure="failed := 'B'" _post="n += 1"/></ForceSuccess>
    </Sequence>"""
    h = Harness(xml)
    h["B"].returns(F)
    assert h.tick() == S
    assert h.bb["ok"] == 1.0 and h.bb["failed"] == "B" and h.bb["n"] == 2


def test_on_halted_runs_when_reactive_parent_halts() -> None:
    h = Harness('<ReactiveSequence><Check name="c"/><Stub name="Move" _onHalted="stopped := 1"/></ReactiveSequence>')
    h["c"].returns(S, F)
    h["Move"].returns(R)
    assert h.tick() == R and h.tick() == F
    assert h.bb["stopped"] == 1 and h["Move"].halted == 1


def test_post_conditions_do_not_run_while_running() -> None:
    h = Harness('<Stub name="A" _post="done := true"/>')
    h["A"].returns(R, S)
    assert h.tick() == R and "done" not in h.bb
    assert h.tick() == S and h.bb["done"] == 1.0
