"""Wake-up re-ticks (BT.CPP ``tickOnce``): within one control period the root runs again while a node asked
for it; robot leaves still do one period of work per tick; an endless request is an error naming the node."""

from __future__ import annotations

import pytest

from bt_grasp.tree.exceptions import TreeRuntimeError

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


def test_endless_wake_ups_are_an_error_naming_the_node() -> None:
    h = Harness('<Repeat name="forever" num_cycles="-1"><AlwaysSuccess/></Repeat>')
    with pytest.raises(TreeRuntimeError, match=r"Repeat 'forever' requested a wake-up 10000 times"):
        h.tick()


def test_a_wake_up_does_not_rerun_a_completed_root() -> None:
    h = Harness('<Sequence><Repeat num_cycles="2"><Stub name="A"/></Repeat><Stub name="B"/></Sequence>')
    # run 1: A, Repeat yields; run 2: A again, Repeat SUCCESS, B SUCCESS -> SUCCESS; no third run
    assert h.tick() == S and h.tree.runs == 2 and h["B"].ticks == 1
