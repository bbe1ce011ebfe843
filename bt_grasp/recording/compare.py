"""`compare_tick_streams`: where a re-simulated run first departs from the recorded one.

Both streams are sequences of ticks, each either a `TickRecord` (from `open_log`) or a `StreamTick`
``{"tick": int, "stamp_ns": int (optional), "nodes": [{"uid": int, "status": str, ...}, ...]}`` — the node
records a tree runtime hands to `RunRecorder.write_tick` (all nodes, or only the changed ones: the streams are
accumulated, a node never written counts as IDLE).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, NotRequired, TypedDict

from bt_grasp.recording.reader import TickRecord


class StreamNode(TypedDict):
    """A node's status in a ``StreamTick`` (a ``tree.records.NodeRecord`` has these keys and more)."""

    uid: int
    status: str
    path: NotRequired[str]


class StreamTick(TypedDict):
    """One tick of a stream given as data rather than read from a log."""

    tick: int
    stamp_ns: NotRequired[int | None]
    nodes: Sequence[StreamNode]


@dataclass(frozen=True)
class NodeDifference:
    uid: int
    path: str
    recorded: str | None
    new: str | None


@dataclass(frozen=True)
class Divergence:
    """The first tick at which the streams differ.

    ``kind``: "status" (some node's status differs; ``differences`` lists them), "recorded_ended" or
    "new_ended" (one stream stops while the other goes on). ``recorded`` and ``new`` hold every node's
    status at that tick on each side (uid -> status).
    """

    tick: int
    kind: Literal["status", "recorded_ended", "new_ended"]
    differences: tuple[NodeDifference, ...]
    recorded: dict[int, str]
    new: dict[int, str]
    recorded_stamp_ns: int | None = None
    new_stamp_ns: int | None = None

    def describe(self) -> str:
        if self.kind != "status":
            side = "recorded run" if self.kind == "recorded_ended" else "new run"
            return f"the {side} ends before tick {self.tick}"
        parts = [f"{d.path or d.uid}: recorded {d.recorded}, new {d.new}" for d in self.differences]
        return f"tick {self.tick}: " + "; ".join(parts)


@dataclass(frozen=True)
class _Tick:
    tick: int
    stamp_ns: int | None
    nodes: tuple[tuple[int, str, str], ...]  # uid, status, path


def _normalise(ticks: Sequence[TickRecord | StreamTick]) -> Iterator[_Tick]:
    for t in ticks:
        if isinstance(t, TickRecord):
            yield _Tick(t.tick, t.stamp_ns, tuple((n.uid, n.status, "") for n in t.nodes))
        else:
            nodes = tuple((int(n["uid"]), str(n["status"]), str(n.get("path", ""))) for n in t["nodes"])
            stamp = t.get("stamp_ns")
            yield _Tick(int(t["tick"]), None if stamp is None else int(stamp), nodes)


def compare_tick_streams(
    recorded_ticks: Sequence[TickRecord | StreamTick],
    new_ticks: Sequence[TickRecord | StreamTick],
    *,
    stop_at_shorter: bool = False,
) -> Divergence | None:
    """The first tick where any node's status differs, or None when the streams agree.

    With ``stop_at_shorter`` (a truncated recording), a stream that ends early is not a divergence.
    """
    recorded = {t.tick: t for t in _normalise(recorded_ticks)}
    new = {t.tick: t for t in _normalise(new_ticks)}
    rec_state: dict[int, str] = {}
    new_state: dict[int, str] = {}
    paths: dict[int, str] = {}
    last_rec, last_new = max(recorded, default=None), max(new, default=None)
    for tick in sorted(recorded.keys() | new.keys()):
        r, n = recorded.get(tick), new.get(tick)
        if last_rec is None or tick > last_rec:
            if stop_at_shorter:
                return None
            return Divergence(tick, "recorded_ended", (), dict(rec_state), dict(new_state),
                              None, n.stamp_ns if n else None)
        if last_new is None or tick > last_new:
            if stop_at_shorter:
                return None
            return Divergence(tick, "new_ended", (), dict(rec_state), dict(new_state),
                              r.stamp_ns if r else None, None)
        for source, state in ((r, rec_state), (n, new_state)):
            for uid, status, path in source.nodes if source else ():
                state[uid] = status
                if path:
                    paths.setdefault(uid, path)
        diffs = tuple(
            NodeDifference(uid, paths.get(uid, ""), rec_state.get(uid, "IDLE"), new_state.get(uid, "IDLE"))
            for uid in sorted(rec_state.keys() | new_state.keys())
            if rec_state.get(uid, "IDLE") != new_state.get(uid, "IDLE")
        )
        if diffs:
            return Divergence(tick, "status", diffs, dict(rec_state), dict(new_state),
                              r.stamp_ns if r else None, n.stamp_ns if n else None)
    return None
