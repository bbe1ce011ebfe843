"""The run fingerprint: what "the same run" means, defined once.

Two runs are the same run when their fingerprints are equal. A fingerprint holds, per tick:

- every node's status and failure reason (keyed by the node's uid; the reason is the ``FailureReason`` code,
  not the human sentence);
- the whole blackboard, as the log stores it (``to_jsonable``; a ``repr`` fallback has its memory addresses
  removed), except the entries in ``INPUT_FILE_KEYS``: where the run's input files lay on disk (a re-simulation
  rebuilds the same files from the log's attachments elsewhere; what was loaded from them, e.g. the
  calibration, is on the blackboard and counts);
- the six arm joint positions, rounded to ``JOINT_RESOLUTION_RAD`` (1e-6 rad), and the gripper width rounded
  to ``WIDTH_RESOLUTION_M`` (1e-6 m);

and, once, the final pose of every object (simulator ground truth, read by the judge at the end of the run:
position to 1e-6 m, rotation matrix entries to 1e-6). Wall-clock quantities (stamps of the machine, time
spent, feedback sentences that may quote them) are not part of it. Simulated stamps are implied by the tick
number.

``Fingerprint.digest`` is a stable SHA-256 (hex) of all of it: equal digests, same run. When two digests
differ, :meth:`Fingerprint.first_difference` names the first differing tick and what differs there (which
nodes, which blackboard keys, which joints, the gripper, or the final poses).

Building one:

- from a recorded log: :func:`fingerprint_of_log` (``bt-grasp replay --resim`` compares the recorded and the
  re-simulated run this way);
- while a run goes, with no log: a :class:`FingerprintRecorder` is a ``TickRecorder`` (``write_tick`` /
  ``write_event`` / ``flush_tick``) to hand to ``TreeRunner`` (or to call from a recorder that forwards), then
  ``finish(final_object_poses)``. Campaign workers use this to compare episodes across machines.

Both paths turn the same values into the same prints (a run recorded and fingerprinted live gives the same
digest as its log).
"""

from __future__ import annotations

import functools
import hashlib
import json
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.files.json_types import JsonValue
from bt_grasp.recording.jsonable import BlackboardDiffer, to_jsonable

if TYPE_CHECKING:  # a run's fingerprint is taken with neither the reader nor the tree package imported
    from bt_grasp.recording.reader import NodeUpdate, RunLog
    from bt_grasp.tree.records import NodeRecord

#: joint positions are compared to this resolution
JOINT_RESOLUTION_RAD = 1e-6
#: the gripper width is compared to this resolution
WIDTH_RESOLUTION_M = 1e-6
#: final object positions (m) and rotation-matrix entries are compared to this resolution
POSE_RESOLUTION = 1e-6
#: the blackboard is converted as the log converts it (recording.writer's default)
MAX_ARRAY_ELEMENTS = 64

#: blackboard entries naming input files by path: not part of the fingerprint (their content is)
INPUT_FILE_KEYS = frozenset({"calibration_file"})

_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")


def _quantise(values: Iterable[float], resolution: float) -> tuple[int, ...]:
    return tuple(round(float(v) / resolution) for v in values)


def _canonical(value: object) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=True)
    return _ADDRESS.sub("", text)


@dataclass(frozen=True)
class TickPrint:
    """One tick's part of the fingerprint."""

    tick: int
    nodes: tuple[tuple[int, str, str | None], ...]  # (uid, status, failure reason), every node seen so far
    blackboard: tuple[tuple[str, str], ...]  # (key, canonical JSON of the value), sorted by key
    q: tuple[int, ...] | None  # joint positions in units of JOINT_RESOLUTION_RAD (None: no arm state)
    gripper: int | None  # gripper width in units of WIDTH_RESOLUTION_M
    #: ``_canonical(blackboard)``, when the recorder has it already (one text shared by every tick the blackboard
    #: did not change in); not part of what is compared
    blackboard_text: str | None = field(default=None, compare=False, repr=False)

    @functools.cached_property
    def digest(self) -> str:
        """SHA-256 of ``_canonical([tick, nodes, blackboard, q, gripper])``, assembled from its five parts' texts:
        JSON joins a list's items with "," and the address pattern lies inside one JSON string, never across two
        parts, so the text is the same; the blackboard's part (kilobytes of JSON text, the same for most ticks)
        is not encoded and searched again for every tick (issue 27: 44 ms of each campaign episode)."""
        board = self.blackboard_text if self.blackboard_text is not None else _canonical(self.blackboard)
        payload = (f"[{_canonical(self.tick)},{_canonical(self.nodes)},{board},{_canonical(self.q)},"
                   f"{_canonical(self.gripper)}]")
        return hashlib.sha256(payload.encode()).hexdigest()


@dataclass(frozen=True)
class FingerprintDifference:
    """Where two fingerprints first part.

    ``tick`` is the first tick whose print differs (None when only the final object poses differ);
    ``what`` lists the differing parts in words ("node 12 (pick/Approach): RUNNING/- vs FAILURE/COLLISION",
    "blackboard grasp", "joint 3: 1.234567 vs 1.234568 rad", "gripper", "run length", "final pose of box").
    """

    tick: int | None
    what: tuple[str, ...]

    def describe(self) -> str:
        where = "at the end" if self.tick is None else f"at tick {self.tick}"
        return f"the runs differ {where}: " + "; ".join(self.what)


@dataclass(frozen=True)
class Fingerprint:
    ticks: tuple[TickPrint, ...]
    final_objects: tuple[tuple[str, tuple[int, ...]], ...]  # (name, quantised 3x4 of T_world_object), sorted
    node_paths: Mapping[int, str] = field(default_factory=dict, compare=False)

    @property
    def digest(self) -> str:
        h = hashlib.sha256()
        for t in self.ticks:
            h.update(t.digest.encode())
        h.update(_canonical(self.final_objects).encode())
        return h.hexdigest()

    def to_json(self) -> dict[str, JsonValue]:
        """The digest, the tick count and the per-tick digests (enough to find a first differing tick)."""
        return {"digest": self.digest, "ticks": len(self.ticks), "tick_digests": [t.digest for t in self.ticks],
                "final_objects": [name for name, _ in self.final_objects]}

    def first_difference(self, other: Fingerprint, *, compare_final: bool = True) -> FingerprintDifference | None:
        """None when ``other`` is the same run; else the first differing tick and what differs there.

        ``compare_final=False`` compares the common ticks only (a truncated log: its run never ended).
        """
        for a, b in zip(self.ticks, other.ticks, strict=False):
            if a.digest != b.digest:
                return FingerprintDifference(a.tick, tuple(self._explain(a, b, other)))
        if not compare_final:
            return None
        if len(self.ticks) != len(other.ticks):
            shorter = min(len(self.ticks), len(other.ticks))
            return FingerprintDifference(shorter + 1, (f"run length: {len(self.ticks)} vs {len(other.ticks)} ticks",))
        if self.final_objects != other.final_objects:
            mine, theirs = dict(self.final_objects), dict(other.final_objects)
            names = sorted(n for n in mine.keys() | theirs.keys() if mine.get(n) != theirs.get(n))
            return FingerprintDifference(None, tuple(f"final pose of {n}" for n in names))
        return None

    def _explain(self, a: TickPrint, b: TickPrint, other: Fingerprint) -> list[str]:
        out = []
        na = {uid: (s, r) for uid, s, r in a.nodes}
        nb = {uid: (s, r) for uid, s, r in b.nodes}
        for uid in sorted(na.keys() | nb.keys()):
            if na.get(uid) != nb.get(uid):
                path = self.node_paths.get(uid) or other.node_paths.get(uid) or ""
                sa, ra = na.get(uid, ("IDLE", None))
                sb, rb = nb.get(uid, ("IDLE", None))
                out.append(f"node {uid} ({path}): {sa}/{ra or '-'} vs {sb}/{rb or '-'}")
        ba, bb = dict(a.blackboard), dict(b.blackboard)
        out += [f"blackboard {k}" for k in sorted(ba.keys() | bb.keys()) if ba.get(k) != bb.get(k)]
        if a.q != b.q:
            if a.q is None or b.q is None:
                out.append("arm state recorded on one side only")
            else:
                out += [f"joint {j}: {qa * JOINT_RESOLUTION_RAD:.6f} vs {qb * JOINT_RESOLUTION_RAD:.6f} rad"
                        for j, (qa, qb) in enumerate(zip(a.q, b.q, strict=True)) if qa != qb]
        if a.gripper != b.gripper:
            out.append("gripper width")
        return out


class FingerprintRecorder:
    """Builds a fingerprint tick by tick; a ``TickRecorder`` (the runner's recorder interface).

    ``write_tick`` takes the runner's node records (``uid``, ``status``, ``failure_reason``; every node or only
    the changed ones: states accumulate), the full blackboard and the arm state (``q_rad``,
    ``gripper_width_m``); ``write_logged_tick`` the same as a log holds them (only the changed blackboard
    entries, and the removed ones).
    """

    def __init__(self) -> None:
        self._nodes: dict[int, tuple[str, str | None]] = {}
        self._paths: dict[int, str] = {}
        self._board: dict[str, str] = {}
        self._differ = BlackboardDiffer(MAX_ARRAY_ELEMENTS)
        self._ticks: list[TickPrint] = []
        self._board_items: tuple[tuple[str, str], ...] = ()  # the board sorted by key, and its canonical text,
        self._board_text = _canonical(self._board_items)  # remade only when the board changed

    def write_tick(self, tick: int, stamp_ns: int, nodes: Sequence[NodeRecord], blackboard: Mapping[str, object],
                   robot: Mapping[str, object] | None = None) -> None:
        for n in nodes:
            uid = int(n["uid"])
            reason = n.get("failure_reason")
            self._nodes[uid] = (str(n["status"]), None if reason is None else str(reason))
            if n.get("path"):
                self._paths.setdefault(uid, str(n["path"]))
        # the whole blackboard, as a run hands it over: convert only what changed
        changed, removed = self._differ.diff(blackboard)
        self._end_tick(tick, changed, removed, robot)

    def write_logged_tick(self, tick: int, nodes: Iterable[NodeUpdate], changed: Mapping[str, JsonValue],
                          removed: Iterable[str], robot: Mapping[str, object] | None) -> None:
        """One tick as a log holds it: the nodes written, the blackboard entries changed and removed."""
        for n in nodes:
            self._nodes[n.uid] = (n.status, n.failure_reason)
        self._end_tick(tick, changed, removed, robot)

    def _end_tick(self, tick: int, changed: Mapping[str, object], removed: Iterable[str],
                  robot: Mapping[str, object] | None) -> None:
        dirty = False
        for key, value in changed.items():
            if key in INPUT_FILE_KEYS:
                continue
            self._board[str(key)] = _canonical(to_jsonable(value, MAX_ARRAY_ELEMENTS))
            dirty = True
        for key in removed:
            dirty = self._board.pop(key, None) is not None or dirty
        if dirty:
            self._board_items = tuple(sorted(self._board.items()))
            self._board_text = _canonical(self._board_items)
        q: tuple[int, ...] | None = None
        gripper: int | None = None
        if robot is not None:
            q = _quantise(np.asarray(robot["q_rad"], dtype=float).ravel(), JOINT_RESOLUTION_RAD)
            width = robot.get("gripper_width_m")
            gripper = None if width is None else _quantise(np.asarray([width], dtype=float), WIDTH_RESOLUTION_M)[0]
        nodes_now = tuple((uid, s, r) for uid, (s, r) in sorted(self._nodes.items()))
        self._ticks.append(TickPrint(int(tick), nodes_now, self._board_items, q, gripper, self._board_text))

    def write_event(self, stamp_ns: int, kind: str, payload: Mapping[str, object]) -> None:
        """Events repeat what the ticks hold (failures): not part of the fingerprint."""

    def flush_tick(self) -> None:
        """Nothing to flush."""

    def finish(self, final_object_poses: Mapping[str, object] | None = None) -> Fingerprint:
        """The fingerprint, with every object's final ``T_world_object`` (4x4, the judge's ground truth)."""
        final = []
        for name, T in sorted((final_object_poses or {}).items()):
            M = np.asarray(T, dtype=float).reshape(4, 4)[:3, :]
            final.append((str(name), _quantise(M.ravel(), POSE_RESOLUTION)))
        return Fingerprint(tuple(self._ticks), tuple(final), dict(self._paths))


def final_object_poses(result: Mapping[str, object] | None) -> dict[str, object]:
    """The final object poses a run's result holds (``judge.object_poses``), or an empty dict."""
    judge = (result or {}).get("judge") or {}
    poses = judge.get("object_poses") if isinstance(judge, Mapping) else None
    return dict(poses) if isinstance(poses, Mapping) else {}


def fingerprint_of_log(run: RunLog) -> Fingerprint:
    """The fingerprint of a recorded run."""
    robot_by_tick: dict[int, dict[str, object]] = {}
    for _, state in run.joint_states():
        tick = state.get("tick")
        if tick is not None:
            robot_by_tick[int(tick)] = {"q_rad": state["position"], "gripper_width_m": state.get("gripper_width_m")}
    recorder = FingerprintRecorder()
    for node in run.nodes.values():
        recorder._paths[node.uid] = node.path
    for record in run.ticks:
        recorder.write_logged_tick(record.tick, record.nodes, record.bb, record.bb_removed,
                                   robot_by_tick.get(record.tick))
    return recorder.finish(final_object_poses(run.result))
