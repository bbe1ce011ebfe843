"""What `bt-grasp replay` shows, as data: summary, status changes, failures and recoveries, one tick's tree.

Everything here reads a `RunLog` and returns plain values (dataclasses, dicts) that the command renders
with rich or prints as JSON. Retries are derived from the tick stream: an attempt of a node starts when it
is ticked while not RUNNING; it is a retry when that node's previous attempt ended in FAILURE. A retry
loop that completes inside one tick (BT.CPP's RetryUntilSuccessful with a synchronous child) is invisible
to a per-tick record.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, replace

from bt_grasp.errors import InputError
from bt_grasp.files.json_types import JsonObject
from bt_grasp.recording.messages import LoggedTreeNode
from bt_grasp.recording.reader import NodeInfo, NodeUpdate, RunLog, message_to_jsonable
from bt_grasp.recording.replay_shapes import (
    AnnotatedNode,
    FaultMarkJson,
    LeafState,
    ReplaySummary,
    TickView,
    TopicRecord,
)
from bt_grasp.tree.failure_kinds import false_by_design

_RECOVERY_LIMIT = 6


@dataclass(frozen=True)
class StatusChange:
    tick: int
    stamp_ns: int
    uid: int
    name: str
    path: str
    old: str
    new: str
    feedback: str
    failure_reason: str | None


class FailureKind:
    """How a failure bears on the run (``FailureReport.kind``)."""

    #: the failure the run ended on: it reached the root, or it is the result's failed leaf at the end
    OUTCOME = "outcome"
    #: a leaf failed (with a reason, or an action with none) and the tree went on: a retry or a recovery
    RECOVERED = "recovered"
    #: false by design: a condition that answered "no" without a reason (``FailureIs`` in a Fallback) or a
    #: decorator that fails by itself (``ForceFailure``, ``Inverter``): control flow, not a fault
    BY_DESIGN = "by_design"


@dataclass(frozen=True)
class FailureReport:
    tick: int
    stamp_ns: int
    uid: int
    name: str
    path: str
    reason: str | None
    propagated_to: tuple[str, ...]
    recovery: tuple[StatusChange, ...]
    kind: str = FailureKind.RECOVERED  # a FailureKind value

    @property
    def decided(self) -> bool:
        return self.kind == FailureKind.OUTCOME


def _info(run: RunLog, uid: int) -> NodeInfo:
    return run.nodes.get(uid) or NodeInfo(uid, f"#{uid}", "", f"#{uid}")


def status_changes(run: RunLog) -> list[StatusChange]:
    """Every change of a node's status, in tick order and, within a tick, in the order written."""
    nodes = run.nodes
    last: dict[int, str] = {}
    out: list[StatusChange] = []
    for record in run.ticks:
        for node in record.nodes:
            old = last.get(node.uid, "IDLE")
            if node.status != old:
                info = nodes.get(node.uid) or NodeInfo(node.uid, f"#{node.uid}", "", f"#{node.uid}")
                out.append(StatusChange(record.tick, record.stamp_ns, node.uid, info.name, info.path, old,
                                        node.status, node.feedback, node.failure_reason))
            last[node.uid] = node.status
    return out


def attempts(run: RunLog) -> dict[int, tuple[int, int, int]]:
    """uid -> (attempts, failures, retries) derived from the tick stream (see the module docstring)."""
    status: dict[int, str] = {}
    outcome: dict[int, str] = {}
    counts: dict[int, list[int]] = {}
    for record in run.ticks:
        for node in record.nodes:
            c = counts.setdefault(node.uid, [0, 0, 0])
            previous = status.get(node.uid, "IDLE")
            if node.ticked and previous != "RUNNING":
                c[0] += 1
                if outcome.get(node.uid) == "FAILURE":
                    c[2] += 1
            if node.status in ("SUCCESS", "FAILURE") and (node.ticked or previous != node.status):
                outcome[node.uid] = node.status
                if node.status == "FAILURE":
                    c[1] += 1
            status[node.uid] = node.status
    return {uid: (c[0], c[1], c[2]) for uid, c in counts.items()}


def _ancestors(nodes: dict[int, NodeInfo], uid: int) -> list[int]:
    chain = []
    parent = nodes[uid].parent if uid in nodes else None
    while parent is not None:
        chain.append(parent)
        parent = nodes[parent].parent if parent in nodes else None
    return chain


def failures(run: RunLog) -> list[FailureReport]:
    """Every leaf FAILURE (or a non-leaf one whose children did not fail that tick), with what ran next."""
    nodes = run.nodes
    changes = status_changes(run)
    failed_at: dict[int, set[int]] = {}
    for ch in changes:
        if ch.new == "FAILURE":
            failed_at.setdefault(ch.tick, set()).add(ch.uid)
    reports = []
    for index, ch in enumerate(changes):
        if ch.new != "FAILURE":
            continue
        same_tick = failed_at[ch.tick]
        info = nodes.get(ch.uid)
        children_failed = any(nodes[u].parent == ch.uid for u in same_tick if u in nodes)
        if info is not None and not info.is_leaf and children_failed:
            continue  # a parent that failed because its child did: reported with the child
        ancestors = _ancestors(nodes, ch.uid)
        propagated = tuple(_info(run, u).path or _info(run, u).name for u in ancestors if u in same_tick)
        excluded = set(ancestors)  # parents going RUNNING again are not news; the failed leaf re-running is
        recovery = tuple(
            later for later in changes[index + 1:]
            if later.new in ("RUNNING", "SUCCESS") and later.uid not in excluded
        )[:_RECOVERY_LIMIT]
        reached = 0  # how far up the FAILURE went this tick, parent by parent
        while reached < len(ancestors) and ancestors[reached] in same_tick:
            reached += 1
        root_failed = bool(ancestors) and reached == len(ancestors)
        if root_failed or (info is not None and not ancestors and not info.is_leaf):
            kind = FailureKind.OUTCOME
        elif _false_by_design(nodes, info, ch.failure_reason):
            kind = FailureKind.BY_DESIGN
        else:
            kind = FailureKind.RECOVERED
        reports.append(FailureReport(ch.tick, ch.stamp_ns, ch.uid, ch.name, ch.path, ch.failure_reason,
                                     propagated, recovery, kind))
    _mark_result_leaf(run, reports)
    return reports


def _false_by_design(nodes: dict[int, NodeInfo], info: NodeInfo | None, reason: str | None) -> bool:
    """The tick loop's rule (``bt_grasp.tree.failure_kinds``) applied to a logged node; a node the log does not
    describe is by design when it gave no reason."""
    if info is None:
        return reason is None
    parent = nodes.get(info.parent) if info.parent is not None else None
    return false_by_design(is_leaf=info.is_leaf, kind=info.kind, parent_type=parent.type if parent else None,
                           reason=reason)


def _mark_result_leaf(run: RunLog, reports: list[FailureReport]) -> None:
    """A run that failed without its root failing (the tick limit, an unmet goal): the result's failed leaf,
    at its last failure, is what decided the outcome."""
    result = run.result or {}
    if result.get("success") is not False or any(r.decided for r in reports):
        return
    wanted = result.get("failed_path") or result.get("failed_leaf")
    for index in range(len(reports) - 1, -1, -1):
        report = reports[index]
        if wanted and wanted in (report.path, report.name) and report.kind != FailureKind.BY_DESIGN:
            reports[index] = replace(report, kind=FailureKind.OUTCOME)
            return


def failure_chain(run: RunLog) -> list[FailureReport]:
    """The causal chain of the run's failures, oldest first: every failure that was not false by design."""
    return [f for f in failures(run) if f.kind != FailureKind.BY_DESIGN]


def _int_or_none(text: str | None) -> int | None:
    """A metadata value that holds an integer, as an int (None when absent or not an integer)."""
    try:
        return int(text) if text is not None else None
    except ValueError:
        return None


def summary(run: RunLog) -> ReplaySummary:
    """The replay summary as JSON-able data."""
    meta = run.metadata
    counts = attempts(run)
    nodes = run.nodes
    per_leaf = {_info(run, uid).path or _info(run, uid).name: c[2] for uid, c in counts.items()
                if c[2] and (uid not in nodes or nodes[uid].is_leaf or not nodes[uid].kind)}
    every_failure = failures(run)
    failures_per_leaf = Counter(f.path or f.name for f in every_failure if f.kind != FailureKind.BY_DESIGN)
    by_design_per_leaf = Counter(f.path or f.name for f in every_failure if f.kind == FailureKind.BY_DESIGN)
    first, last = (run.ticks[0], run.ticks[-1]) if run.ticks else (None, None)
    sim_s = (last.stamp_ns - first.stamp_ns) * 1e-9 if first and last else 0.0
    result = run.result or {}
    retries = result.get("retries")
    return {
        "file": str(run.path),
        "tree": meta.get("tree_file", ""),
        "scene": meta.get("scene_file", ""),
        "seed": _int_or_none(meta.get("seed")),  # MCAP metadata is text: the seed is a number here
        "fault_plan": meta.get("fault_plan", ""),
        "success": result.get("success"),
        "interrupted": bool(result.get("interrupted")),  # Ctrl-C ended the run (success is null)
        "reason": result.get("reason"),
        "failed_leaf": result.get("failed_leaf"),
        "failed_path": result.get("failed_path"),
        "ticks": len(run.ticks),
        "first_tick": first.tick if first else None,
        "last_tick": last.tick if last else None,
        "sim_duration_s": round(sim_s, 6),
        "retries": retries if retries is not None else sum(per_leaf.values()),
        "retries_per_leaf": dict(sorted(per_leaf.items())),
        "failures_per_leaf": dict(sorted(failures_per_leaf.items())),  # not the ones false by design:
        "false_by_design_per_leaf": dict(sorted(by_design_per_leaf.items())),  # conditions asked, ForceFailure
        "truncated": run.truncated,
        "ticks_recovered": run.ticks_recovered,
        "result": run.result,
        "topics": run.topics,
        "faults": [{k: v for k, v in f.items()} for f in run.faults],
        "interventions": list(run.interventions),
        "events": len(run.events),
        "metadata": meta,
        "attachments": sorted(run.attachments),
    }


def timeline(run: RunLog) -> list[tuple[int, int, list[StatusChange]]]:
    """(tick, stamp_ns, changes) for every tick in which some node changed status."""
    rows: list[tuple[int, int, list[StatusChange]]] = []
    for ch in status_changes(run):
        if not rows or rows[-1][0] != ch.tick:
            rows.append((ch.tick, ch.stamp_ns, []))
        rows[-1][2].append(ch)
    return rows


@dataclass(frozen=True)
class FaultMark:
    """An injected fault that fired, as the text timeline marks it: its name (label), kind, the node or object it
    hit (``target``: the leaf's path when the log names one node by it, else the leaf's name, the nudged object or
    the trigger), the tick and simulated time, and what it did (``effect``)."""

    tick: int
    stamp_ns: int
    label: str
    kind: str
    target: str
    effect: str

    def as_json(self) -> FaultMarkJson:
        return {"tick": self.tick, "stamp_ns": self.stamp_ns, "label": self.label, "kind": self.kind,
                "target": self.target, "effect": self.effect}

    def text(self) -> str:
        """``frame_drop@Perceive#1 (frame_drop) on pick/Perceive: no frame``"""
        kind = f" ({self.kind})" if self.kind and self.kind != self.label else ""
        target = f" on {self.target}" if self.target else ""
        return f"{self.label}{kind}{target}" + (f": {self.effect}" if self.effect else "")


def _text(value: object) -> str:
    return "" if value is None else str(value)


def _mapping(value: object) -> JsonObject:
    return value if isinstance(value, dict) else {}


def fault_marks(run: RunLog) -> list[FaultMark]:
    """Every injected fault that fired (the log's /faults), in tick order, for the timeline."""
    by_name: dict[str, list[str]] = {}
    for node in run.nodes.values():
        by_name.setdefault(node.name, []).append(node.path or node.name)
    marks = []
    for record in run.faults:
        recorded = record.get("fault")
        fault: JsonObject = recorded if isinstance(recorded, dict) else {"label": _text(recorded)}
        details, params, trigger = (_mapping(fault.get(k)) for k in ("details", "params", "trigger"))
        leaf = _text(fault.get("leaf"))
        paths = by_name.get(leaf, [])
        target = (paths[0] if len(paths) == 1 else leaf) or _text(params.get("object")) or _text(
            trigger.get("on_leaf")) or _text(fault.get("target"))
        tick = record.get("tick")
        marks.append(FaultMark(
            tick=int(tick) if isinstance(tick, int) and not isinstance(tick, bool) else -1,
            stamp_ns=int(record.get("stamp_ns", 0)),
            label=_text(fault.get("label") or fault.get("name") or fault.get("kind")) or "fault",
            kind=_text(fault.get("kind")),
            target=target,
            effect=_text(details.get("effect")),
        ))
    return sorted(marks, key=lambda m: (m.tick, m.stamp_ns))


def find_nodes(run: RunLog, name: str) -> list[NodeInfo]:
    """Nodes whose name, path or uid is ``name``; raises InputError naming the choices when none is."""
    nodes = run.nodes
    found = [n for n in nodes.values() if name in (n.name, n.path, str(n.uid))]
    if not found:
        leaves = sorted({n.name for n in nodes.values() if n.is_leaf} or {n.name for n in nodes.values()})
        raise InputError("--leaf", f"no node named {name!r} in {run.path.name}; nodes: {', '.join(leaves)}")
    return sorted(found, key=lambda n: n.uid)


def leaf_history(run: RunLog, name: str) -> list[LeafState]:
    """Every written state of the named node(s): tick, status, feedback, reason, ticked."""
    uids = {n.uid for n in find_nodes(run, name)}
    out: list[LeafState] = []
    for record in run.ticks:
        for node in record.nodes:
            if node.uid in uids:
                out.append({"tick": record.tick, "stamp_ns": record.stamp_ns, "uid": node.uid, "status": node.status,
                            "feedback": node.feedback, "failure_reason": node.failure_reason, "ticked": node.ticked,
                            "name": _info(run, node.uid).name})
    return out


def check_tick(run: RunLog, tick: int) -> None:
    if not run.ticks:
        raise InputError("--tick", f"{run.path.name} holds no ticks")
    if run.tick_record(tick) is None:
        raise InputError("--tick", f"tick {tick} is not in {run.path.name} "
                                   f"(ticks {run.ticks[0].tick}..{run.ticks[-1].tick})")


def tree_at(run: RunLog, tick: int) -> AnnotatedNode:
    """The recorded structure at ``tick`` with each node's status, feedback and reason, as nested dicts."""
    check_tick(run, tick)
    states = run.states_at(tick)
    record = run.tick_record(tick)
    ticked_now = {n.uid for n in record.nodes if n.ticked} if record else set()
    snapshot = run.structure_at(tick)

    def annotate(node: LoggedTreeNode) -> AnnotatedNode:
        state = states.get(int(node["uid"]), NodeUpdate(int(node["uid"]), "IDLE"))
        return {
            "uid": state.uid, "name": node.get("name", ""), "type": node.get("type", ""),
            "kind": node.get("kind", ""), "path": node.get("path", ""), "status": state.status,
            "feedback": state.feedback, "failure_reason": state.failure_reason,
            "ticked": state.uid in ticked_now,
            "children": [annotate(child) for child in node.get("children", [])],
        }

    if snapshot is not None:
        return annotate(snapshot.root)
    # no structure recorded: a flat list under a synthetic root
    flat: list[LoggedTreeNode] = [{"uid": uid, "name": info.name, "type": info.type, "path": info.path,
                                   "children": []} for uid, info in sorted(run.nodes.items())]
    return annotate({"uid": -1, "name": "(no tree structure recorded)", "type": "", "children": flat})


def tick_view(run: RunLog, tick: int) -> TickView:
    record = run.tick_record(tick)
    tree = tree_at(run, tick)
    faults = [mark.as_json() for mark in fault_marks(run) if mark.tick == tick]  # those that fired in this tick
    return {"tick": tick, "stamp_ns": record.stamp_ns if record else None, "tree": tree,
            "blackboard": run.blackboard_at(tick), "robot": run.robot_at(tick), "faults": faults}


def topic_messages(run: RunLog, topic: str) -> Iterator[TopicRecord]:
    """Messages of one topic as JSON-able dicts; InputError when the log has no such topic."""
    if topic not in run.topics:
        choices = ", ".join(run.topics)
        raise InputError("--topic", f"{run.path.name} has no topic {topic!r}; topics: {choices}")
    for msg in run.iter_messages(topic):
        yield {"topic": topic, "log_time_ns": msg.log_time_ns, "publish_time_ns": msg.publish_time_ns,
               "message": message_to_jsonable(msg.message)}


__all__ = [
    "FailureKind",
    "FailureReport",
    "StatusChange",
    "attempts",
    "failure_chain",
    "failures",
    "find_nodes",
    "leaf_history",
    "status_changes",
    "summary",
    "tick_view",
    "timeline",
    "topic_messages",
    "tree_at",
]
