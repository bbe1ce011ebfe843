"""Wake-up re-ticks (BT.CPP ``tickOnce``): within one control period the root runs again while a node asked
for it; robot leaves still do one period of work per tick; endless requests are capped per period and the
loop goes on in the next one."""

from __future__ import annotations

from bt_grasp.tree.node import WAKE_UP_LIMIT

from .harness import Harness, R, S

PARALLEL = (
    '<Parallel success_count="-1"><{leaf} name="Move"/><Repeat num_cycles="3"><Stub name="A"/></Repeat></Parallel>'
)


def test_a_plain_leaf_is_ticked_by_every_root_run() -> None:
    h = Harness(PARALLEL.format(leaf="Stub"))
    h["Move"].returns(R)
    # tick 1: three root executions (Repeat yields twice); Move RUNNING is ticked by each, as in BT.CPP
    assert h.tick() == R and h.tree.runs == 3 and h["Move"].ticks == 3


def test_a_robot_leaf_advances_once_per_control_period() -> None:
    h = Harness(PARALLEL.format(leaf="Arm"))
    h["Move"].returns(R, R, S)
    # tick 1: three root executions, but the RUNNING robot leaf's update() runs once
    assert h.tick() == R and h.tree.runs == 3 and h["Move"].ticks == 1
    # tick 2: one root execution (the Parallel does not re-tick the completed Repeat); one update
    assert h.tick() == R and h["Move"].ticks == 2
    # tick 3: Move SUCCESS -> every child succeeded -> SUCCESS
    assert h.tick() == S and h["Move"].ticks == 3


def test_endless_wake_ups_are_capped_per_period_and_yield_to_the_next() -> None:
    h = Harness('<Repeat name="forever" num_cycles="-1"><Stub name="A"/></Repeat>')
    # tick 1: WAKE_UP_LIMIT root executions, one A SUCCESS each, then the period ends RUNNING (no error)
    assert h.tick() == R and h.tree.runs == WAKE_UP_LIMIT and h["A"].ticks == WAKE_UP_LIMIT
    assert h.tree.root.bt_wake_up.capped and "Repeat 'forever'" in h.tree.root.bt_wake_up.requester
    # tick 2: the loop goes on where it stopped, as many again
    assert h.tick() == R and h["A"].ticks == 2 * WAKE_UP_LIMIT


def test_a_timeout_ends_an_endless_loop_in_simulated_time() -> None:
    h = Harness(
        '<Fallback><Timeout msec="20"><Repeat num_cycles="-1"><AlwaysSuccess/></Repeat></Timeout>'
        '<Stub name="After"/></Fallback>'
    )
    # tick 1 at t=0 ms: capped, RUNNING; tick 2 at 10 ms: capped, RUNNING; tick 3 at 20 ms: the Timeout
    # halts the Repeat and fails -> the Fallback ticks After -> SUCCESS (BT.CPP: its timer thread does this)
    assert h.tick() == R and h.tree.root.bt_wake_up.capped
    h.clock.advance_s(0.010)
    assert h.tick() == R and h["After"].ticks == 0
    h.clock.advance_s(0.010)
    assert h.tick() == S and h["After"].ticks == 1 and not h.tree.root.bt_wake_up.capped


def test_a_wake_up_does_not_rerun_a_completed_root() -> None:
    h = Harness('<Sequence><Repeat num_cycles="2"><Stub name="A"/></Repeat><Stub name="B"/></Sequence>')
    # run 1: A, Repeat yields; run 2: A again, Repeat SUCCESS, B SUCCESS -> SUCCESS; no third run
    assert h.tick() == S and h.tree.runs == 2 and h["B"].ticks == 1
