"""Turning blackboard values into JSON, and keeping only what changed from one tick to the next.

Conversions (documented in docs/recording.md):

- numbers, strings, booleans, None: as they are; a non-finite float becomes the string "nan", "inf" or "-inf"
  (JSON has no such numbers and Foxglove rejects them);
- numpy scalars: the Python number; numpy arrays up to ``max_array_elements`` values: nested lists; larger
  arrays: a summary ``{"__ndarray__": {"shape", "dtype", "min", "max", "mean"}}`` (a point cloud on the
  blackboard must not be logged 100 times a second);
- dataclasses: a dict of their fields plus ``"__type__"``; enums: their name; paths: a string; bytes: their
  length; sets: a sorted list; tuples: lists; mappings: dicts with string keys;
- an object with a ``to_dict()`` method: what it returns; anything else: its ``repr`` (at most 200 chars).
"""

from __future__ import annotations

import dataclasses
import enum
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import PurePath
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.recording.messages import NodeEntry

if TYPE_CHECKING:  # the tree package is not imported in the writer process (writer_process.py)
    from bt_grasp.tree.records import NodeRecord

_SCALARS = (str, int, bool, type(None))
_REPR_LIMIT = 200


def _float(value: float) -> float | str:
    if math.isfinite(value):
        return value
    return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")


def _array(value: NDArray[np.generic], max_elements: int) -> JsonValue:
    if value.size > max_elements:
        summary: JsonObject = {"shape": list(value.shape), "dtype": str(value.dtype)}
        if value.size and np.issubdtype(value.dtype, np.number):
            finite = value[np.isfinite(value)] if np.issubdtype(value.dtype, np.floating) else value
            if finite.size:
                summary.update(min=float(finite.min()), max=float(finite.max()), mean=float(finite.mean()))
        return {"__ndarray__": summary}
    if value.dtype.kind == "f" and not np.isfinite(value).all():
        return to_jsonable(value.tolist(), max_elements)
    if value.dtype.kind in "biuf":
        numbers: JsonValue = value.tolist()
        return numbers
    return to_jsonable(value.tolist(), max_elements)


def to_jsonable(value: object, max_array_elements: int = 64) -> JsonValue:
    """A JSON-serialisable copy of ``value`` (see the module docstring for the rules)."""
    if isinstance(value, _SCALARS):
        return value
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, np.ndarray):
        return _array(value, max_array_elements)
    if isinstance(value, np.generic):
        return to_jsonable(value.item(), max_array_elements)
    if isinstance(value, enum.Enum):
        return value.name
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out: JsonObject = {"__type__": type(value).__name__}
        for field in dataclasses.fields(value):
            out[field.name] = to_jsonable(getattr(value, field.name), max_array_elements)
        return out
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v, max_array_elements) for k, v in value.items()}
    if isinstance(value, (set, frozenset)):
        return sorted((to_jsonable(v, max_array_elements) for v in value), key=repr)
    if isinstance(value, PurePath):
        return str(value)
    if isinstance(value, (bytes, bytearray, memoryview)):
        return {"__bytes__": len(value)}
    if isinstance(value, Sequence):
        return [to_jsonable(v, max_array_elements) for v in value]
    to_dict = getattr(value, "to_dict", None)
    if callable(to_dict):
        return to_jsonable(to_dict(), max_array_elements)
    text = repr(value)
    return text if len(text) <= _REPR_LIMIT else text[: _REPR_LIMIT - 3] + "..."


def _is_immutable_leaf(value: object) -> bool:
    return isinstance(value, (*_SCALARS, float, enum.Enum, PurePath, np.generic))


def _is_frozen(value: object, depth: int = 0) -> bool:
    """Values that cannot change while they stay the same object: immutable scalars, frozen dataclasses
    (the pipeline's results, whose arrays are never written after construction), tuples of those."""
    if _is_immutable_leaf(value):
        return True
    params = getattr(type(value), "__dataclass_params__", None)
    if params is not None:
        return bool(params.frozen)
    pydantic = sys.modules.get("pydantic")  # not imported: nothing can be a pydantic model (the writer process)
    if pydantic is not None and isinstance(value, pydantic.BaseModel):  # pydantic models (the calibration file)
        return bool(value.model_config.get("frozen", False))
    if isinstance(value, tuple) and depth < 2:
        return all(_is_frozen(v, depth + 1) for v in value)
    return False


_MISSING = object()


def _same_array(last: object, value: NDArray[np.generic]) -> bool:
    """Whether ``last`` (the remembered copy) is an array equal to ``value`` (NaNs equal to NaNs)."""
    return (
        isinstance(last, np.ndarray)
        and last.shape == value.shape
        and last.dtype == value.dtype
        and bool(np.array_equal(last, value, equal_nan=value.dtype.kind in "fc"))
    )


class BlackboardDiffer:
    """Remembers the last value written per key; ``diff`` returns only the keys that changed."""

    def __init__(self, max_array_elements: int = 64) -> None:
        self._max = max_array_elements
        self._raw: dict[str, object] = {}
        self._json: JsonObject = {}
        # whether the remembered value is frozen: decided once (it cannot change while it is the same object,
        # which ``_raw`` keeps alive), not every tick (the recursion over tuples was a third of write_tick)
        self._frozen: dict[str, bool] = {}

    def diff(self, blackboard: Mapping[str, object]) -> tuple[JsonObject, list[str]]:
        """(changed keys with their JSON values, keys that disappeared since the last call)."""
        changed: JsonObject = {}
        raw, frozen = self._raw, self._frozen
        for key, value in blackboard.items():
            last = raw.get(key, _MISSING)
            if last is value and frozen[key]:  # the same immutable object (most entries, most ticks)
                continue
            if isinstance(value, np.ndarray) and _same_array(last, value):  # arrays: compared by value
                continue
            converted = to_jsonable(value, self._max)
            if key not in self._json or self._json[key] != converted:
                changed[key] = converted
                self._json[key] = converted
            self._raw[key] = self._remember(value)
            self._frozen[key] = _is_frozen(value)  # arrays are compared by value instead
        # every key of ``blackboard`` is in ``_raw`` now: keys went away only if ``_raw`` holds more
        removed = [key for key in self._raw if key not in blackboard] if len(self._raw) > len(blackboard) else []
        for key in removed:
            del self._raw[key]
            del self._json[key]
            del self._frozen[key]
        return changed, removed

    @staticmethod
    def _remember(value: object) -> object:
        return value.copy() if isinstance(value, np.ndarray) else value


class NodeDiffer:
    """Keeps, per node uid, the last status/feedback/reason written.

    ``diff`` returns the entries to write for this tick: nodes ticked this tick or whose status, feedback or
    failure reason changed. The first time a uid is written its path, type and name go with it, so a tick
    stream can be read even without the tree structure.
    """

    def __init__(self) -> None:
        self._last: dict[int, tuple[str, str, str | None]] = {}

    def reset(self) -> None:
        self._last.clear()

    def diff(self, nodes: Sequence[NodeRecord]) -> list[NodeEntry]:
        out: list[NodeEntry] = []
        last_of = self._last
        for node in nodes:
            uid = node["uid"]
            if type(uid) is not int:
                uid = int(uid)
            state = (node["status"], node.get("feedback") or "", node.get("failure_reason"))
            last = last_of.get(uid)
            ticked = bool(node.get("ticked"))
            if not ticked and last == state:
                continue
            entry: NodeEntry
            if state[2] is None:  # left out when none (Foxglove's JSON schemas have no nullable types)
                entry = {"uid": uid, "status": state[0], "feedback": state[1], "ticked": ticked}
            else:
                entry = {"uid": uid, "status": state[0], "feedback": state[1], "failure_reason": state[2],
                         "ticked": ticked}
            if last is None:  # the names, in this order (the log's bytes)
                if "path" in node:
                    entry["path"] = node["path"]
                if "type" in node:
                    entry["type"] = node["type"]
                if "name" in node:
                    entry["name"] = node["name"]
            self._last[uid] = state
            out.append(entry)
        return out
