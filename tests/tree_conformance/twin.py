"""Run a corpus tree through bt_grasp the way tools/btcpp_diff/driver.cpp runs it through BT.CPP, and produce
the same JSON shape, so the two can be compared field by field."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from bt_grasp.clock import ManualClock
from bt_grasp.errors import TreeFileError
from bt_grasp.tree import BtNode, load_tree
from bt_grasp.tree.blackboard import EMPTY
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtStatus

from .leaves import Traces, conformance_registry

_LETTER = {"IDLE": "I", "RUNNING": "R", "SUCCESS": "S", "FAILURE": "F", "SKIPPED": "K"}


def _preorder(node: BtNode) -> list[BtNode]:
    found = [node]
    for child in node.children:
        found.extend(_preorder(child))  # type: ignore[arg-type]
    return found


def typed(value: Any) -> dict[str, Any]:
    """A blackboard value as the driver prints it."""
    if value is EMPTY:
        return {"type": "empty"}
    if isinstance(value, bool):
        return {"type": "bool", "value": value}
    if isinstance(value, str):
        return {"type": "str", "value": value}
    if isinstance(value, int):
        return {"type": "int", "value": value}
    if isinstance(value, float):
        if math.isnan(value):
            return {"type": "real", "value": "nan"}
        if math.isinf(value):
            return {"type": "real", "value": "inf" if value > 0 else "-inf"}
        return {"type": "real", "value": value}
    return {"type": "other", "value": type(value).__name__}


def run_tree(path: Path, max_ticks: int = 20, period_ms: int = 0) -> dict[str, Any]:
    """Load and tick ``path`` like the driver: one ``tick()`` per control period, stop when it completes."""
    traces = Traces()
    clock = ManualClock()
    try:
        tree = load_tree(path, conformance_registry(traces), clock=clock)
    except TreeFileError as exc:
        return {"status": "ERROR", "error": {"phase": "load", "message": str(exc)}}
    nodes = _preorder(tree.root)[1:]
    transitions: list[list[Any]] = []
    ticks = 0

    def changed(node: BtNode, previous: BtStatus, new: BtStatus) -> None:
        transitions.append([ticks, node.bt_path, previous.value, new.value])

    for node in tree.nodes():
        node.bt_on_change = changed
    statuses: list[str] = []
    runs: list[int] = []
    snapshots: list[str] = []
    error = None
    status = "IDLE"
    try:
        while ticks < max_ticks:
            ticks += 1
            status = tree.tick().value
            if status in ("SUCCESS", "FAILURE"):  # BT.CPP's tickOnce resets a completed root at once
                transitions.append([ticks, tree.root.bt_path, status, "IDLE"])
            statuses.append(status)
            runs.append(tree.runs)
            snapshots.append("".join(_LETTER[n.bt_state.value] for n in nodes))
            if status in ("SUCCESS", "FAILURE"):
                break
            clock.advance_ns(max(period_ms, 1) * 1_000_000)
    except TreeRuntimeError as exc:
        error = {"phase": "tick", "message": str(exc)}
    blackboard = {
        key: typed(entry.value)
        for key in sorted(tree.root_blackboard.keys())
        if (entry := tree.root_blackboard.entry(key)) is not None
    }
    return {
        "status": "ERROR" if error else status,
        "ticks": ticks,
        "statuses": statuses,
        "runs": runs,
        "nodes": snapshots,
        "paths": [n.bt_path for n in nodes],
        "blackboard": blackboard,
        "leaves": traces.as_json(),
        "transitions": transitions,
        "error": error,
    }
