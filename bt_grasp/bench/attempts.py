"""`bt-grasp bench attempts LOG_OR_DIR ...`: the attempts of recorded runs, counted from their logs (issue 46).

For each log: the attempts it made (``/bt/attempts``; a log written before that channel existed, format 1-3, has
its grasp attempts rebuilt from the leaves' statuses and the ``grasp`` blackboard entry: each start of
``Approach`` is one, ended by the next failure of Approach, Grasp or Lift, or Lift's success), the pairs where a
later attempt repeats a failed earlier one by the rules of ``bt_grasp.behaviours.attempts`` (same object, same
family, within 5 mm and 10 degrees; within 15 mm and 20 degrees of a grasp that stalled), and whether the run
succeeded. The summary: episodes, failed episodes, episodes with a repeat, repeats, and the distribution of
attempts per failed episode.
"""

from __future__ import annotations

import statistics
from collections import Counter
from collections.abc import Iterable
from pathlib import Path
from typing import TypedDict

import numpy as np

from bt_grasp.behaviours.attempts import Attempt, AttemptKind, ObjectSeen, grasp_family, outcome_of, repeats
from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.recording.reader import RunLog, open_log


class LogAttempts(TypedDict):
    log: str
    success: bool | None
    attempts: int  # attempts made (notices that nothing was tried are not counted)
    grasps: int
    places: int
    repeats: list[tuple[int, int]]
    rebuilt: bool  # rebuilt from the leaves' statuses (a log without /bt/attempts)


class AttemptSummary(TypedDict):
    episodes: int
    failed: int
    episodes_with_repeats: int
    repeats: int
    attempts_per_failed_episode: dict[int, int]  # attempts -> episodes
    attempts_per_failed_episode_median: float
    attempts_per_episode_mean: float
    logs: list[LogAttempts]


def log_files(paths: Iterable[Path]) -> list[Path]:
    """The .mcap files named, and those in the folders named (sorted)."""
    out: list[Path] = []
    for p in paths:
        out.extend(sorted(p.rglob("*.mcap")) if p.is_dir() else [p])
    return out


def attempts_of(log: RunLog) -> tuple[list[JsonObject], bool]:
    """The log's attempts as ``/bt/attempts`` messages, and whether they were rebuilt (no such channel)."""
    if log.attempts or log.metadata.get("log_format", "1") not in ("1", "2", "3"):
        return list(log.attempts), False
    return rebuilt_grasps(log), True


def rebuilt_grasps(log: RunLog) -> list[JsonObject]:
    """Grasp attempts of a log written before ``/bt/attempts``: each start of Approach (the grasp on the
    blackboard then: its pose, width and target), ended by the next failure of Approach, Grasp or Lift (its
    reason) or by Lift's success."""
    kinds = {uid: info.type for uid, info in log.nodes.items()}
    bb: dict[str, JsonValue] = {}
    out: list[JsonObject] = []
    open_: JsonObject | None = None
    status: dict[int, str] = {}
    for tick in log.ticks:
        bb.update(tick.bb)
        for key in tick.bb_removed:
            bb.pop(key, None)
        for node in tick.nodes:
            kind, before = kinds.get(node.uid, ""), status.get(node.uid, "IDLE")
            status[node.uid] = node.status
            if kind == "Approach" and node.status == "RUNNING" and before != "RUNNING":
                if open_ is not None:
                    out.append(open_)
                open_ = _grasp_message(len(out), tick.tick, bb)
            elif open_ is not None and kind in ("Approach", "Grasp", "Lift") and node.status == "FAILURE":
                out.append(_ended(open_, node.failure_reason or "FAILED", tick.tick, kind))
                open_ = None
            elif open_ is not None and kind == "Lift" and node.status == "SUCCESS" and before != "SUCCESS":
                out.append(_ended(open_, None, tick.tick, kind))
                open_ = None
    if open_ is not None:
        out.append(open_)
    return [m for m in out if m]


def _matrix(value: JsonValue) -> np.ndarray | None:
    try:
        T = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return T if T.shape == (4, 4) else None


def _grasp_message(index: int, tick: int, bb: dict[str, JsonValue]) -> JsonObject:
    """The attempt the blackboard's grasp and target stand for (empty when they are not there)."""
    from bt_grasp.perception.results import Detection

    grasp, target = bb.get("grasp"), bb.get("target")
    candidate = grasp.get("candidate", grasp) if isinstance(grasp, dict) else None
    T = _matrix(candidate.get("T_base_tcp_grasp")) if isinstance(candidate, dict) else None
    if T is None or not isinstance(target, dict) or not isinstance(candidate, dict):
        return {}
    width = candidate.get("width_m")
    width_m = float(width) if isinstance(width, int | float) else 0.0
    centroid, size, yaw = target.get("centroid_base_m"), target.get("size_m"), target.get("yaw_rad")
    if not (isinstance(centroid, list) and isinstance(size, list) and isinstance(yaw, int | float)):
        return {}
    det = Detection(label=str(target.get("label", "")), pixel_box=(0, 0, 0, 0),
                    centroid_base_m=(float(centroid[0]), float(centroid[1]), float(centroid[2])),  # type: ignore[arg-type]
                    size_m=(float(size[0]), float(size[1]), float(size[2])),  # type: ignore[arg-type]
                    yaw_rad=float(yaw), point_count=0, confidence=0.0,
                    class_name=str(target.get("class_name", "") or ""))
    attempt = Attempt(index, AttemptKind.GRASP, "Approach", tick, ObjectSeen.of(det), T,
                      grasp_family(T, width_m, det), "-", width_m=width_m, moved=True)
    return attempt.to_json()


def _ended(message: JsonObject, reason: str | None, tick: int, leaf: str) -> JsonObject:
    if not message:
        return message
    outcome = outcome_of(reason)
    if outcome.value == "STALLED" and leaf != "Approach":
        outcome = outcome.__class__.FAILED
    return {**message, "outcome": outcome.value, "reason": reason or "", "end_tick": tick, "end_leaf": leaf}


def count_log(path: Path) -> LogAttempts:
    log = open_log(path)
    messages, rebuilt = attempts_of(log)
    made = [m for m in messages if m.get("outcome") != "SKIPPED"]
    success = log.result.get("success") if log.result is not None else None
    return {
        "log": str(path), "success": success if isinstance(success, bool) else None, "attempts": len(made),
        "grasps": sum(1 for m in made if m.get("kind") == "grasp"),
        "places": sum(1 for m in made if m.get("kind") == "place"),
        "repeats": repeats(made), "rebuilt": rebuilt,
    }


def summarise(paths: Iterable[Path]) -> AttemptSummary:
    logs = [count_log(p) for p in log_files(paths)]
    failed = [entry for entry in logs if entry["success"] is False]
    per_failed = Counter(entry["attempts"] for entry in failed)
    return {
        "episodes": len(logs),
        "failed": len(failed),
        "episodes_with_repeats": sum(1 for entry in logs if entry["repeats"]),
        "repeats": sum(len(entry["repeats"]) for entry in logs),
        "attempts_per_failed_episode": dict(sorted(per_failed.items())),
        "attempts_per_failed_episode_median": statistics.median([e["attempts"] for e in failed]) if failed else 0.0,
        "attempts_per_episode_mean": round(statistics.mean([e["attempts"] for e in logs]), 2) if logs else 0.0,
        "logs": logs,
    }
