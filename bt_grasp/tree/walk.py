"""A run's walk as BehaviorTree.CPP's loggers show it: every status change of every node, in order.

BT.CPP's ``StatusChangeLogger`` (the base of ``StdCoutLogger`` and of Groot2's ``FileLogger2``) is told of each
change of a node's stored status: IDLE -> RUNNING when a control starts, RUNNING -> SUCCESS when it completes,
SUCCESS -> IDLE when its parent resets it, RUNNING -> IDLE when a parent halts it. A skipped node keeps IDLE (no
change). :class:`WalkRecorder` watches the same changes through each node's ``bt_on_change`` and stamps them
with the control period (tick) and the simulated time they happened at; the differential corpus checks that the
list equals BT.CPP 4.10's for every tree without wall-clock timers (``tests/tree_conformance``).

One difference of bt_grasp's engine is made up for here: BT.CPP's ``tickOnce`` resets a root that completed to
IDLE at once (``Tree::tickRoot``), while bt_grasp's root keeps its status until the next tick; the recorder adds
that reset after a tick whose root completed (:meth:`WalkRecorder.end_tick`), so the list is BT.CPP's.

:func:`stdout_lines` prints it with ``StdCoutLogger``'s columns, the node's full path in place of its name:
``[0.010]: pick/attempt/Lift         RUNNING -> SUCCESS`` (time in simulated seconds since the first tick).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from bt_grasp.tree.node import BtNode, BtStatus

#: StdCoutLogger pads the name to this many characters
NAME_COLUMN = 25


@dataclass(frozen=True)
class Transition:
    """One status change: the tick (control period, from 1), simulated ns since the first tick, the node's uid,
    full path and type, its previous and new status."""

    tick: int
    time_ns: int
    uid: int
    path: str
    node_type: str
    previous: str
    new: str

    def as_json(self) -> dict[str, object]:
        return {"tick": self.tick, "time_s": round(self.time_ns / 1e9, 9), "path": self.path,
                "type": self.node_type, "from": self.previous, "to": self.new}


@dataclass(frozen=True)
class TickSummary:
    """One tick: its number, the root's status after it, how many times it executed the root (wake-up re-runs)."""

    tick: int
    status: str
    runs: int

    def as_json(self) -> dict[str, object]:
        return {"tick": self.tick, "status": self.status, "runs": self.runs}


@dataclass
class WalkRecorder:
    """Watches every node of a tree (``bt_on_change``) and keeps the status changes in order.

    Call :meth:`start_tick` before each tick with its number and simulated time, :meth:`end_tick` after it."""

    root: BtNode
    transitions: list[Transition] = field(default_factory=list)
    ticks: list[TickSummary] = field(default_factory=list)
    _tick: int = 0
    _time_ns: int = 0

    def attach(self, nodes: Iterable[BtNode]) -> WalkRecorder:
        for node in nodes:
            node.bt_on_change = self._changed
        return self

    def _changed(self, node: BtNode, previous: BtStatus, new: BtStatus) -> None:
        self.transitions.append(
            Transition(self._tick, self._time_ns, node.bt_uid, node.bt_path, node.bt_type, previous.value, new.value))

    def start_tick(self, tick: int, time_ns: int) -> None:
        self._tick, self._time_ns = tick, time_ns

    def end_tick(self, status: BtStatus, runs: int) -> None:
        """The tick ended with the root ``status`` after ``runs`` executions; a completed root is reset to IDLE
        in the walk, as BT.CPP's ``tickOnce`` does at once."""
        if status.completed:
            self._changed(self.root, status, BtStatus.IDLE)
        self.ticks.append(TickSummary(self._tick, status.value, runs))


def stdout_line(move: Transition) -> str:
    """One transition in ``StdCoutLogger``'s columns: ``[time]: path<padded to 25> PREVIOUS -> NEW``."""
    pad = " " * max(0, NAME_COLUMN - len(move.path))
    return f"[{move.time_ns / 1e9:.3f}]: {move.path}{pad} {move.previous} -> {move.new}"


def stdout_lines(ticks: Iterable[TickSummary], transitions: Iterable[Transition]) -> list[str]:
    """The walk as text: ``tick N: STATUS`` (with the root executions when a wake-up re-ran it), then that tick's
    transitions in ``StdCoutLogger``'s columns."""
    by_tick: dict[int, list[Transition]] = {}
    for move in transitions:
        by_tick.setdefault(move.tick, []).append(move)
    lines = []
    for tick in ticks:
        runs = f" ({tick.runs} root runs)" if tick.runs > 1 else ""
        lines.append(f"tick {tick.tick}: {tick.status}{runs}")
        lines.extend(stdout_line(move) for move in by_tick.get(tick.tick, ()))
    return lines
