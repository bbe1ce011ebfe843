"""Built-in actions, tick by tick (BT.CPP src/actions and include/behaviortree_cpp/actions)."""

from __future__ import annotations

import pytest

from bt_grasp.tree.exceptions import TreeRuntimeError

from .harness import F, Harness, S


def test_unset_blackboard_removes_the_entry() -> None:
    h = Harness(
        '<Sequence><Script code="x := 1; y := 2"/><UnsetBlackboard key="x"/><UnsetBlackboard key="no"/></Sequence>'
    )
    # tick 1: x removed, a missing key is no error -> SUCCESS
    assert h.tick() == S and h.bb == {"y": 2} and not h.tree.root_blackboard.exists("x")


def test_was_entry_updated_remembers_per_node() -> None:
    h = Harness('<Sequence><Script code="x := 1"/><WasEntryUpdated entry="x"/></Sequence>')
    # tick 1: x written (sequence 1, the node last saw 0) -> SUCCESS
    assert h.tick() == S
    h2 = Harness(
        '<Sequence><Script code="x := 1"/>'
        '<KeepRunningUntilFailure><WasEntryUpdated entry="{x}"/></KeepRunningUntilFailure></Sequence>'
    )
    # tick 1: updated -> SUCCESS -> KeepRunningUntilFailure RUNNING; tick 2: not written since -> FAILURE
    assert h2.tick() == "RUNNING" and h2.tick() == F
    h3 = Harness('<WasEntryUpdated entry="never"/>')
    # tick 1: no such entry -> FAILURE
    assert h3.tick() == F


def test_set_blackboard_converts_text_to_the_entry_type() -> None:
    h = Harness(
        '<Sequence><Script code="n := 1"/><SetBlackboard value="41" output_key="n"/><Script code="n += 1"/></Sequence>'
    )
    # the entry holds an integer, so "41" becomes 41; n += 1 keeps it an integer
    assert h.tick() == S and h.bb["n"] == 42 and isinstance(h.bb["n"], int)
    h2 = Harness('<Sequence><Script code="n := 1"/><SetBlackboard value="abc" output_key="n"/></Sequence>')
    with pytest.raises(TreeRuntimeError, match="needs an integer"):
        h2.tick()


def test_set_blackboard_copies_an_entry() -> None:
    h = Harness('<Sequence><Script code="a := 2.5"/><SetBlackboard value="{a}" output_key="b"/></Sequence>')
    assert h.tick() == S and h.bb["b"] == 2.5
