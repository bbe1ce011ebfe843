"""Ticking a loaded tree in simulated time: tick, record, step the world one control period, repeat.

The runner owns no robot or simulator: it receives a :class:`bt_grasp.interfaces.Stepper` (the world),
an optional recorder and a callable that reads the arm state. One tick per control period; the physics
steps between ticks; timeouts inside the tree read the same simulated clock.

A tick is BT.CPP's ``tickOnce``: the root may execute several times within it (wake-up re-runs, see
:class:`bt_grasp.tree.node.WakeUp`). ``max_ticks``, the outcome's ``ticks`` and ``/bt/tick`` count control
periods: one ``/bt/tick`` record per period, with each node's status after the last root execution and
``ticked`` when any execution ticked it; a period with re-runs also writes a ``wake_up`` event
(``{"tick", "runs"}``), and the outcome's ``root_runs`` counts every root execution.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol, TypedDict

from bt_grasp.interfaces import Stepper
from bt_grasp.tree.failure_kinds import false_by_design
from bt_grasp.tree.introspect import bt_status_name
from bt_grasp.tree.loader import LoadedTree
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.records import NodeRecord
from bt_grasp.tree.registry import NodeKind

log = logging.getLogger(__name__)


class TickRecorder(Protocol):
    def write_tick(
        self,
        tick: int,
        stamp_ns: int,
        nodes: Sequence[NodeRecord],
        blackboard: Mapping[str, object],
        robot: Mapping[str, object] | None = None,
    ) -> None: ...

    def write_event(self, stamp_ns: int, kind: str, payload: Mapping[str, object]) -> None: ...

    def flush_tick(self) -> None: ...


class TickStatuses(TypedDict):
    """One tick of :attr:`TreeRunner.stream`: every node's status as recorded, by path."""

    tick: int
    status: dict[str, str]


class TickGate(Protocol):
    """Consulted between ticks (``bt_grasp.control.Controller``): once before the first tick (tick 0) and after
    every tick that did not end the run, before the physics steps; it may hold (a paused run: simulated time
    stands still). ``failures``: every FAILURE a leaf returned in the tick, each saying whether it was false by
    design. Returns True to stop the run there."""

    def between_ticks(self, tick: int, failures: Sequence[FailureEvent] = ()) -> bool: ...


@dataclass
class FailureEvent:
    """A leaf's FAILURE. ``by_design``: a condition asked by a Fallback (or answering "no" with no reason):
    control flow, not a fault. ``followed``: what came of it, filled in when the run ends ("retried at tick
    N", "the run ended", "the tree went on without it")."""

    tick: int
    stamp_ns: int
    leaf: str
    path: str
    reason: str | None
    message: str
    by_design: bool = False
    followed: str = ""


@dataclass
class RunOutcome:
    """How a run ended, as the tree saw it (the physics judge is separate)."""

    status: str  # SUCCESS, FAILURE, or RUNNING when max_ticks ran out
    ticks: int
    sim_time_s: float
    wall_time_s: float
    failures: list[FailureEvent] = field(default_factory=list)
    #: every leaf FAILURE that was not by design, in order, each with what followed it: the causal chain
    chain: list[FailureEvent] = field(default_factory=list)
    retried: dict[str, int] = field(default_factory=dict)  # leaf path -> attempts started after a FAILURE
    root_runs: int = 0  # root executions, wake-up re-runs included (>= ticks)
    stopped: bool = False  # a TickGate stopped the run (an operator's Stop)

    @property
    def retries(self) -> dict[str, int]:
        """Leaf path (its one name in every output) -> how many times it was tried again after it had failed."""
        return dict(self.retried)

    @property
    def last_failure(self) -> FailureEvent | None:
        return self.failures[-1] if self.failures else None


class TreeRunner:
    """Runs one tree to completion (or ``max_ticks``) against a stepper."""

    def __init__(
        self,
        tree: LoadedTree,
        stepper: Stepper,
        *,
        steps_per_tick: int,
        recorder: TickRecorder | None = None,
        robot_state: Callable[[], Mapping[str, object]] | None = None,
        on_tick: Callable[[int, LoadedTree], None] | None = None,
        gate: TickGate | None = None,
        on_failure: Callable[[FailureEvent], None] | None = None,
    ) -> None:
        self.tree = tree
        self.stepper = stepper
        self.steps_per_tick = steps_per_tick
        self.recorder = recorder
        self.robot_state = robot_state
        self.on_tick = on_tick
        self.gate = gate
        #: called as it happens with each leaf FAILURE that is not by design (the CLI's live failure line)
        self.on_failure = on_failure
        self._watch = _TickWatch()
        for node in tree.nodes():
            node.bt_listener = self._watch
        #: every node in uid order, walked once: a tree's structure does not change while it runs
        self._nodes = sorted(tree.nodes(), key=lambda n: n.bt_uid)
        #: per tick, every node's status as recorded (path -> status), for comparing runs
        self.stream: list[TickStatuses] = []

    def run(self, max_ticks: int) -> RunOutcome:
        start_ns = self.stepper.now_ns()
        wall0 = time.perf_counter()
        failures: list[FailureEvent] = []
        shown: list[tuple[FailureEvent, int]] = []  # the failures not by design, with their listener order
        watch = self._watch
        status = BtStatus.RUNNING
        tick = 0
        root_runs = 0
        gate = self.gate
        stopped = gate is not None and gate.between_ticks(0)
        while tick < max_ticks and not stopped:
            tick += 1
            watch.new_tick(tick)
            status = self.tree.tick()
            root_runs += self.tree.runs
            stamp = self.stepper.now_ns()
            if self.tree.runs > 1 and self.recorder is not None:
                self.recorder.write_event(stamp, "wake_up", {"tick": tick, "runs": self.tree.runs})
            records = tick_records(self._nodes, watch)
            self.stream.append({"tick": tick, "status": {rec["path"]: rec["status"] for rec in records}})
            # every FAILURE a leaf returned during this tick, also those a retry inside the tick hid again
            this_tick: list[FailureEvent] = []
            for node, reason, message, order in watch.failed:
                event = FailureEvent(tick, stamp, node.name, node.bt_path, reason, message, false_by_design(
                    is_leaf=True, kind=node.bt_kind.value, parent_type=_parent_type(node), reason=reason))
                this_tick.append(event)
                if reason is not None:
                    failures.append(event)
                if not event.by_design:
                    shown.append((event, order))
                    if self.on_failure is not None:
                        self.on_failure(event)
                if self.recorder is not None:
                    self.recorder.write_event(stamp, "failure", event.__dict__)
            if self.recorder is not None:
                robot = dict(self.robot_state()) if self.robot_state is not None else None
                self.recorder.write_tick(tick, stamp, records, self.tree.blackboard_values(), robot)
                self.recorder.flush_tick()
            if self.on_tick is not None:
                self.on_tick(tick, self.tree)
            if status.completed:
                break
            if gate is not None and gate.between_ticks(tick, this_tick):
                stopped = True
                break
            self.stepper.step(self.steps_per_tick)
        if not status.completed:
            self.tree.halt()  # cancel motion of RUNNING leaves
        _what_followed(shown, watch.restarts, status.value if status.completed else "RUNNING")
        sim_s = (self.stepper.now_ns() - start_ns) * 1e-9
        return RunOutcome(
            status=status.value if status.completed else "RUNNING",
            ticks=tick,
            sim_time_s=sim_s,
            wall_time_s=time.perf_counter() - wall0,
            failures=failures,
            chain=[event for event, _ in shown],
            retried=dict(watch.retries),
            root_runs=root_runs,
            stopped=stopped,
        )


def tick_records(nodes: Sequence[BtNode], watch: _TickWatch) -> list[NodeRecord]:
    """One dict per node (``nodes`` in uid order) as the recorders take them: uid, type, name, path, kind,
    status (what the node returned this tick if it was ticked: a Sequence resets a failed child to IDLE
    afterwards; else its BT.CPP status), failure_reason, ticked, feedback."""
    ticked_now, returned = watch.ticked, watch.returned
    records: list[NodeRecord] = []
    for node in nodes:
        uid = node.bt_uid
        ticked = uid in ticked_now
        records.append({
            "uid": uid, "type": node.bt_type, "name": node.name, "path": node.bt_path, "kind": node.bt_kind.value,
            "status": returned[uid] if ticked else bt_status_name(node),
            "failure_reason": getattr(node, "failure_reason", None), "ticked": ticked,
            "feedback": node.feedback_message,
        })
    return records


class _TickWatch:
    """The nodes' ``bt_listener``: which nodes were ticked this tick, what each returned, every FAILURE a
    leaf returned (with its reason, snapshotted: a retry in the same tick clears it), and retries."""

    def __init__(self) -> None:
        self.ticked: set[int] = set()
        self.returned: dict[int, str] = {}
        self.failed: list[tuple[BtNode, str | None, str, int]] = []
        self.retries: Counter[str] = Counter()
        #: (path, tick, order) of every leaf attempt started after its last attempt failed
        self.restarts: list[tuple[str, int, int]] = []
        self.tick = 0
        self.order = 0  # counts listener calls: what happened first within one tick

    def new_tick(self, tick: int = 0) -> None:
        self.ticked.clear()
        self.failed.clear()
        self.tick = tick

    def __call__(self, node: BtNode, before: BtStatus, result: BtStatus) -> None:
        uid = node.bt_uid
        self.order += 1
        if before is not BtStatus.RUNNING and self.returned.get(uid) == "FAILURE" and not node.children:
            self.restarts.append((node.bt_path, self.tick, self.order))
            if node.bt_kind is NodeKind.ACTION:
                self.retries[node.bt_path] += 1  # a new attempt of an action whose last attempt failed
        self.ticked.add(uid)
        self.returned[uid] = result.value
        if not node.children and result is BtStatus.FAILURE:
            self.failed.append((node, getattr(node, "failure_reason", None), node.feedback_message, self.order))


def _parent_type(node: BtNode) -> str | None:
    parent = node.parent
    return None if parent is None else str(getattr(parent, "bt_type", ""))


def _what_followed(shown: Sequence[tuple[FailureEvent, int]], restarts: Sequence[tuple[str, int, int]],
                   status: str) -> None:
    """Fill in each failure's ``followed``: the retry of the same leaf that came next, else how the run went."""
    for index, (event, order) in enumerate(shown):
        retry = next(((tick, o) for path, tick, o in restarts if path == event.path and o > order), None)
        if retry is not None:
            event.followed = f"retried at tick {retry[0]}"
        elif index + 1 == len(shown):
            event.followed = "the run ended" + (f" ({status})" if status != "RUNNING" else " (tick limit)")
        else:
            event.followed = "the tree went on without retrying it"
