"""LoopInt, LoopDouble, LoopString, LoopBool and application loops, tick by tick (BT.CPP loop_node.h)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import pytest

from bt_grasp.errors import TreeFileError
from bt_grasp.nodes import loop_node
from bt_grasp.tree.exceptions import TreeRuntimeError

from .harness import F, Harness, R, S


def test_loop_int_pops_one_item_per_tick() -> None:
    h = Harness('<LoopInt queue="1;2;3" value="{v}"><Stub name="A"/></LoopInt>')
    # ticks 1-3: pop 1, 2, 3 -> child SUCCESS -> RUNNING; tick 4: empty -> if_empty (SUCCESS)
    seen = []
    for _ in range(3):
        assert h.tick() == R
        seen.append(h.bb["v"])
    assert h.tick() == S and seen == [1, 2, 3] and h["A"].ticks == 3


def test_loop_resumes_a_running_child_without_popping() -> None:
    h = Harness('<LoopInt queue="7;8" value="{v}"><Stub name="A"/></LoopInt>')
    h["A"].returns(R, S, S)
    # tick 1: pop 7, A RUNNING -> RUNNING; tick 2: A SUCCESS (no pop) -> RUNNING; tick 3: pop 8 -> RUNNING
    assert h.tick() == R and h.bb["v"] == 7
    assert h.tick() == R and h.bb["v"] == 7
    assert h.tick() == R and h.bb["v"] == 8
    # tick 4: empty -> SUCCESS
    assert h.tick() == S


def test_loop_fails_when_the_child_fails_and_honours_if_empty() -> None:
    h = Harness('<LoopString queue="a;b" value="{v}"><Stub name="A"/></LoopString>')
    h["A"].returns(F)
    # tick 1: pop 'a', A FAILURE -> FAILURE
    assert h.tick() == F and h.bb["v"] == "a"
    h2 = Harness('<LoopDouble queue="{q}" value="{v}" if_empty="SKIPPED"><Stub name="A"/></LoopDouble>')
    h2.tree.root_blackboard.set("q", deque())
    # tick 1: the queue is empty -> if_empty
    assert h2.tick() == "SKIPPED"


def test_loop_over_a_shared_deque_pops_it_in_place() -> None:
    h = Harness('<LoopBool queue="{q}" value="{v}"><Stub name="A"/></LoopBool>')
    queue = deque([True, False])
    h.tree.root_blackboard.set("q", queue)
    # tick 1: pop True; the deque on the blackboard shrinks
    assert h.tick() == R and h.bb["v"] is True and list(queue) == [False]


def test_loop_queue_of_the_wrong_type_is_refused() -> None:
    # a literal queue is converted at load time: file:line and the port
    with pytest.raises(TreeFileError, match=r"<string>:1: LoopInt: port 'queue': item 'x' is not a int"):
        Harness('<LoopInt queue="1;x" value="{v}"><Stub name="A"/></LoopInt>')
    # a blackboard queue is checked when the loop starts
    h = Harness('<LoopInt queue="{q}" value="{v}"><Stub name="A"/></LoopInt>')
    h.tree.root_blackboard.set("q", ["a"])
    with pytest.raises(TreeRuntimeError, match="not a int"):
        h.tick()


@dataclass(frozen=True)
class Seen:
    """An application type (as issue 11's perceived objects)."""

    label: str


def test_an_application_loop_iterates_its_own_type() -> None:
    xml = '<LoopSeen queue="{objects}" value="{obj}"><Stub name="A"/></LoopSeen>'
    h = Harness(xml, extra=(loop_node("LoopSeen", Seen),))
    h.tree.root_blackboard.set("objects", [Seen("red"), Seen("blue")])
    # tick 1: obj = red; tick 2: obj = blue; tick 3: SUCCESS
    assert h.tick() == R and h.bb["obj"] == Seen("red")
    assert h.tick() == R and h.bb["obj"] == Seen("blue")
    assert h.tick() == S
