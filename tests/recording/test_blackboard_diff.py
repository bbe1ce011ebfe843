"""What the tick record says of the blackboard: only entries that changed, whatever kind of value they hold."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bt_grasp.recording.jsonable import BlackboardDiffer


@dataclass(frozen=True)
class Frozen:
    x: float


@dataclass
class Mutable:
    x: float


def F(x: float) -> dict[str, object]:
    return {"__type__": "Frozen", "x": x}


def test_only_changed_entries_are_written() -> None:
    differ = BlackboardDiffer()
    pose = np.zeros(3)
    items = [1, 2]
    target = (Frozen(1.0), Frozen(2.0))
    state = Mutable(0.5)
    board = {"pose": pose, "items": items, "target": target, "state": state, "name": "red"}

    changed, removed = differ.diff(board)
    assert set(changed) == {"pose", "items", "target", "state", "name"} and removed == []
    assert differ.diff(board) == ({}, [])  # nothing changed: nothing written

    pose[1] = 2.0  # an array written in place
    items.append(3)  # a list grown in place
    state.x = 0.75  # a mutable dataclass written in place
    changed, _ = differ.diff(board)
    assert changed == {"pose": [0.0, 2.0, 0.0], "items": [1, 2, 3], "state": {"__type__": "Mutable", "x": 0.75}}

    board["target"] = (Frozen(1.0), Frozen(2.0))  # a new object, equal to the last: nothing to write
    assert differ.diff(board) == ({}, [])
    board["target"] = (Frozen(1.0), Frozen(3.0))
    assert differ.diff(board)[0] == {"target": [F(1.0), F(3.0)]}

    del board["name"]
    assert differ.diff(board) == ({}, ["name"])
    board["name"] = "blue"  # back again: written as new
    assert differ.diff(board) == ({"name": "blue"}, [])


def test_a_tuple_holding_a_mutable_value_is_checked_every_time() -> None:
    differ = BlackboardDiffer()
    inner = Mutable(1.0)
    board = {"pair": (Frozen(0.0), inner)}
    differ.diff(board)
    inner.x = 2.0  # the same tuple object, but what it holds changed
    assert differ.diff(board)[0] == {"pair": [F(0.0), {"__type__": "Mutable", "x": 2.0}]}
