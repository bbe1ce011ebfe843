"""Ticking a loaded tree in simulated time: tick, record, step the world one control period, repeat.

The runner owns no robot or simulator: it receives a :class:`bt_grasp.interfaces.Stepper` (the world),
an optional recorder and a callable that reads the arm state. One tick per control period; the physics
steps between ticks; timeouts inside the tree read the same simulated clock.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from bt_grasp.interfaces import Stepper
from bt_grasp.tree.introspect import node_records
from bt_grasp.tree.loader import LoadedTree
from bt_grasp.tree.node import BtNode, BtStatus

log = logging.getLogger(__name__)


class TickRecorder(Protocol):
    def write_tick(
        self,
        tick: int,
        stamp_ns: int,
        nodes: list[dict[str, Any]],
        blackboard: Mapping[str, Any],
        robot: Mapping[str, Any] | None = None,
    ) -> None: ...

    def write_event(self, stamp_ns: int, kind: str, payload: Mapping[str, Any]) -> None: ...

    def flush_tick(self) -> None: ...


@dataclass
class FailureEvent:
    tick: int
    stamp_ns: int
    leaf: str
    path: str
    reason: str | None
    message: str


@dataclass
class RunOutcome:
    """How a run ended, as the tree saw it (the physics judge is separate)."""

    status: str  # SUCCESS, FAILURE, or RUNNING when max_ticks ran out
    ticks: int
    sim_time_s: float
    wall_time_s: float
    failures: list[FailureEvent] = field(default_factory=list)
    attempts: dict[str, int] = field(default_factory=dict)  # leaf path -> attempts started
    retried: dict[str, int] = field(default_factory=dict)  # leaf name -> attempts started after a FAILURE

    @property
    def retries(self) -> dict[str, int]:
        """Leaf name -> how many times it was tried again after it had failed."""
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
        robot_state: Callable[[], Mapping[str, Any]] | None = None,
        on_tick: Callable[[int, LoadedTree], None] | None = None,
    ) -> None:
        self.tree = tree
        self.stepper = stepper
        self.steps_per_tick = steps_per_tick
        self.recorder = recorder
        self.robot_state = robot_state
        self.on_tick = on_tick
        self._nodes: list[BtNode] = list(tree.nodes())
        self._counts: dict[int, int] = {}
        self._returned: dict[int, str] = {}
        self._failed_in_tick: list[tuple[BtNode, str | None, str]] = []
        self._retries: Counter[str] = Counter()
        _instrument(self._nodes, self._counts, self._returned, self._failed_in_tick, self._retries)

    def run(self, max_ticks: int) -> RunOutcome:
        start_ns = self.stepper.now_ns()
        wall0 = time.perf_counter()
        attempts: Counter[str] = Counter()
        failures: list[FailureEvent] = []
        previous: dict[int, str] = {n.bt_uid: "IDLE" for n in self._nodes}
        status = BtStatus.RUNNING
        tick = 0
        while tick < max_ticks:
            tick += 1
            before = dict(self._counts)
            self._failed_in_tick.clear()
            status = self.tree.tick()
            stamp = self.stepper.now_ns()
            records = node_records(self.tree.root)
            for rec in records:
                uid = rec["uid"]
                ticked = self._counts.get(uid, 0) != before.get(uid, 0)
                rec["ticked"] = ticked
                # what the node returned this tick (a Sequence resets a failed child to IDLE afterwards)
                rec["status"] = self._returned[uid] if ticked else rec["bt_status"]
                del rec["bt_status"]
                rec["feedback"] = rec.pop("feedback_message")
                if ticked and rec["kind"] in ("Action", "Condition"):
                    # each executeTick starts an attempt, except the first one continuing a RUNNING leaf
                    k = self._counts[uid] - before.get(uid, 0)
                    attempts[rec["path"]] += k - 1 if previous[uid] == "RUNNING" else k
                previous[uid] = rec["status"]
            # every FAILURE a leaf returned during this tick, also those a retry inside the tick hid again
            for node, reason, message in self._failed_in_tick:
                event = FailureEvent(tick, stamp, node.name, node.bt_path, reason, message)
                if reason is not None:
                    failures.append(event)
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
            self.stepper.step(self.steps_per_tick)
        if not status.completed:
            self.tree.halt()  # cancel motion of RUNNING leaves
        sim_s = (self.stepper.now_ns() - start_ns) * 1e-9
        return RunOutcome(
            status=status.value if status.completed else "RUNNING",
            ticks=tick,
            sim_time_s=sim_s,
            wall_time_s=time.perf_counter() - wall0,
            failures=failures,
            attempts=dict(attempts),
            retried=dict(self._retries),
        )


def _instrument(
    nodes: list[BtNode],
    counts: dict[int, int],
    returned: dict[int, str],
    failed: list[tuple[BtNode, str | None, str]],
    retries: Counter[str],
) -> None:
    """Count each node's ticks (BT.CPP ``executeTick`` calls) and keep what it returned, so the recorder
    knows what was ticked and with which result."""
    for node in nodes:
        inner = node.execute_tick
        uid = node.bt_uid
        is_leaf = not node.children
        is_action = node.bt_kind.value == "Action"

        def counted(
            inner: Callable[[], BtStatus] = inner,
            uid: int = uid,
            node: BtNode = node,
            is_leaf: bool = is_leaf,
            is_action: bool = is_action,
        ) -> BtStatus:
            counts[uid] = counts.get(uid, 0) + 1
            if is_action and node.bt_state is not BtStatus.RUNNING and returned.get(uid) == "FAILURE":
                retries[node.name] += 1  # a new attempt of an action whose last attempt failed
            result = inner()
            returned[uid] = result.value
            if is_leaf and result is BtStatus.FAILURE:  # snapshot: a retry in this tick clears them
                failed.append((node, getattr(node, "failure_reason", None), node.feedback_message))
            return result

        node.execute_tick = counted  # type: ignore[method-assign]
