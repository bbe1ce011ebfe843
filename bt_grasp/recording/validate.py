"""The shapes of bt_grasp's own JSON messages, checked once where a log is read.

A log is a file a user gives: a message of the wrong shape (a tick number that is a string, a tree without
its structure, a joint state whose positions are not numbers) must be one sentence naming the file, the topic
and the time, not a traceback somewhere in a view that uses it later. ``parse_json`` decodes and checks one
message and raises ``BadMessage`` with what is wrong; the reader adds the file, topic and time.

Each check returns the message as the shape it checked (``bt_grasp.recording.messages``): the one place a
value read from a file becomes a typed message.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping
from typing import TypeGuard, cast

from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.files.terminal_text import may_hold_controls, shown_deep
from bt_grasp.recording import topics
from bt_grasp.recording.messages import (
    LoggedEvent,
    LoggedFault,
    LoggedIntervention,
    LoggedJointState,
    LoggedResult,
    LoggedTick,
    LoggedTrajectory,
    LoggedTree,
)

#: deeper than any real tree (the views walk trees recursively in places: a hostile depth would crash them)
MAX_TREE_DEPTH = 100
#: integers (ticks, times, uids) a log may hold: what MCAP's own times hold
INT_LIMIT = 2**63
_LONE_SURROGATE_ESCAPE = re.compile(r"\\u[dD][89a-fA-F]")


class BadMessage(ValueError):
    """A message that is not what its topic holds; the text says what is wrong in it."""


def _kind(value: object) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list",
            dict: "an object", type(None): "null"}.get(type(value), type(value).__name__)


def is_int(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool) and -INT_LIMIT <= value < INT_LIMIT


def is_number(value: object) -> TypeGuard[int | float]:
    return (isinstance(value, float) or is_int(value)) and not isinstance(value, bool)


def _need(ok: bool, what: str, value: object, expected: str) -> None:
    if not ok:
        raise BadMessage(f"'{what}' is {_kind(value)}, not {expected}")


def _list(value: JsonValue, what: str, expected: str) -> list[JsonValue]:
    if not isinstance(value, list):
        raise BadMessage(f"'{what}' is {_kind(value)}, not {expected}")
    return value


def _int(msg: JsonObject, key: str, where: str = "", optional: bool = False, null: bool = False) -> None:
    if key not in msg:
        if optional:
            return
        raise BadMessage(f"'{where}{key}' is missing")
    value = msg[key]
    if null and value is None:
        return
    _need(is_int(value), where + key, value, "an integer below 2^63")


def _str(msg: JsonObject, key: str, where: str = "", optional: bool = True, null: bool = False) -> None:
    if key not in msg:
        if optional:
            return
        raise BadMessage(f"'{where}{key}' is missing")
    value = msg[key]
    if null and value is None:
        return
    _need(isinstance(value, str), where + key, value, "a string" + (" or null" if null else ""))


def _numbers(value: JsonValue, what: str, null_ok: bool = False) -> None:
    items = _list(value, what, "a list of numbers")
    if all(type(item) is float for item in items):  # the usual case, fast: a log holds one list per tick
        return
    for i, item in enumerate(items):
        _need(is_number(item) or (null_ok and item is None), f"{what}[{i}]", item, "a number")


def _object(msg: object, what: str = "the message") -> JsonObject:
    if not isinstance(msg, dict):
        raise BadMessage(f"{what} is {_kind(msg)}, not a JSON object")
    return msg


def tick_message(value: JsonValue) -> LoggedTick:
    """A ``/bt/tick`` message, checked."""
    msg = _object(value)
    _int(msg, "tick")
    _int(msg, "stamp_ns")
    nodes = _list(msg.get("nodes", []), "nodes", "a list")
    for i, value_of_node in enumerate(nodes):
        where = f"nodes[{i}]."
        node = _object(value_of_node, f"nodes[{i}]")
        _int(node, "uid", where)
        _str(node, "status", where, optional=False)
        for key in ("feedback", "failure_reason"):
            _str(node, key, where, null=True)
        for key in ("path", "type", "name", "kind"):
            _str(node, key, where)
        if "ticked" in node:
            _need(isinstance(node["ticked"], bool), where + "ticked", node["ticked"], "a boolean")
    if "bb" in msg:
        _need(isinstance(msg["bb"], dict), "bb", msg["bb"], "an object")
    removed = msg.get("bb_removed", [])
    _need(isinstance(removed, list) and all(isinstance(k, str) for k in removed), "bb_removed", removed,
          "a list of strings")
    return cast("LoggedTick", msg)  # what the checks above make sure of


def tree_message(value: JsonValue) -> LoggedTree:
    """A ``/bt/tree`` message, checked."""
    msg = _object(value)
    _int(msg, "tick", optional=True, null=True)
    if "structure" not in msg:
        raise BadMessage("'structure' is missing")
    stack: list[tuple[JsonValue, str, int]] = [(msg["structure"], "structure", 1)]
    while stack:
        value_of_node, where, depth = stack.pop()
        node = _object(value_of_node, where)
        if depth > MAX_TREE_DEPTH:
            raise BadMessage(f"the tree is nested deeper than {MAX_TREE_DEPTH} levels")
        _int(node, "uid", where + ".")
        for key in ("path", "type", "name", "kind"):
            _str(node, key, where + ".")
        if "attributes" in node:  # a node's ports as written: an object (the .btlog export walks it)
            _need(isinstance(node["attributes"], dict), where + ".attributes", node["attributes"], "an object")
        children = _list(node.get("children", []), where + ".children", "a list")
        stack.extend((child, f"{where}.children[{i}]", depth + 1) for i, child in enumerate(children))
    return cast("LoggedTree", msg)  # what the checks above make sure of


def result_message(value: JsonValue) -> LoggedResult:
    """A ``/run/result`` message, checked."""
    msg = _object(value)
    if "success" in msg:
        _need(msg["success"] is None or isinstance(msg["success"], bool), "success", msg["success"], "a boolean")
    for key in ("reason", "failed_leaf"):
        _str(msg, key, null=True)
    for key in ("sim_time_s", "wall_time_s"):
        if msg.get(key) is not None:
            _need(is_number(msg[key]), key, msg[key], "a number")
    if "ticks" in msg:
        _int(msg, "ticks", null=True)
    return cast("LoggedResult", msg)  # what the checks above make sure of


def joint_state_message(value: JsonValue) -> LoggedJointState:
    """A ``/robot/joint_state`` message, checked."""
    msg = _object(value)
    _int(msg, "tick", optional=True, null=True)
    for key in ("position", "velocity", "tcp_xyz_m", "tcp_quat_xyzw"):
        if key in msg:
            _numbers(msg[key], key)
    if "name" in msg:
        _need(isinstance(msg["name"], list) and all(isinstance(n, str) for n in msg["name"]), "name", msg["name"],
              "a list of strings")
    if msg.get("gripper_width_m") is not None:
        _need(is_number(msg["gripper_width_m"]), "gripper_width_m", msg["gripper_width_m"], "a number")
    return cast("LoggedJointState", msg)  # what the checks above make sure of


def trajectory_message(value: JsonValue) -> LoggedTrajectory:
    """A ``/motion/trajectory`` message, checked."""
    msg = _object(value)
    _int(msg, "stamp_ns", optional=True)  # the reader adds it (a message of its own keeps its own)
    if "q_rad" in msg:
        for i, row in enumerate(_list(msg["q_rad"], "q_rad", "a list of joint vectors")):
            _numbers(row, f"q_rad[{i}]", null_ok=True)
    if "points" in msg:
        for i, point in enumerate(_list(msg["points"], "points", "a list")):
            _numbers(_object(point, f"points[{i}]").get("q_rad"), f"points[{i}].q_rad", null_ok=True)
    if "times_s" in msg:
        _numbers(msg["times_s"], "times_s", null_ok=True)
    return cast("LoggedTrajectory", msg)  # what the checks above make sure of


def _stamped(value: JsonValue) -> JsonObject:
    """Events, faults and interventions: free-form, but the reader adds ``stamp_ns`` and the views print
    ``tick``."""
    msg = _object(value)
    _int(msg, "tick", optional=True, null=True)
    _int(msg, "stamp_ns", optional=True)
    return msg


def event_message(value: JsonValue) -> LoggedEvent:
    """A ``/bt/events`` message, checked."""
    return cast("LoggedEvent", _stamped(value))  # what the checks make sure of


def fault_message(value: JsonValue) -> LoggedFault:
    """A ``/faults`` message, checked."""
    return cast("LoggedFault", _stamped(value))  # what the checks make sure of


def attempt_message(value: JsonValue) -> JsonObject:
    """A ``/bt/attempts`` message, checked: its index, kind, outcome and object are there (the rest is shown as
    written; ``bt_grasp.behaviours.attempts.repeats`` reads the poses)."""
    msg = _stamped(value)
    _int(msg, "index")
    for key in ("kind", "outcome", "family"):
        _str(msg, key)
    _object(msg.get("object"), "object")
    return msg


def intervention_message(value: JsonValue) -> LoggedIntervention:
    """A ``/control/interventions`` message, checked (when the reader loads it: the topic is not one
    ``parse_json`` checks, so a log written before interventions were checked still opens)."""
    return cast("LoggedIntervention", _stamped(value))  # what the checks make sure of


#: the check of each of bt_grasp's own JSON topics
CHECKS: dict[str, Callable[[JsonValue], Mapping[str, object]]] = {
    topics.TICK: tick_message, topics.TREE: tree_message, topics.RESULT: result_message,
    topics.JOINT_STATE: joint_state_message, topics.TRAJECTORY: trajectory_message, topics.EVENTS: event_message,
    topics.FAULTS: fault_message, topics.ATTEMPTS: attempt_message,
}


def _check_text(value: JsonValue) -> None:
    """Every string in ``value`` encodes as UTF-8 (a lone surrogate escape, ``"\\udcff"``, does not)."""
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            try:
                item.encode("utf-8")
            except UnicodeEncodeError:
                raise BadMessage("it holds text that is not valid Unicode (a lone surrogate)") from None
        elif isinstance(item, dict):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)


def parse_json(topic: str, data: bytes) -> JsonValue:
    """One JSON message, decoded and, for bt_grasp's own topics, checked; raises ``BadMessage``."""
    msg = json_value(data)
    check = CHECKS.get(topic)
    if check is not None:
        check(msg)
    return msg


def json_value(data: bytes) -> JsonValue:
    """One JSON message, decoded (its strings made safe to print) but not checked; raises ``BadMessage``."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise BadMessage(f"it is not UTF-8 text (byte {exc.start})") from None
    try:
        msg: JsonValue = json.loads(text)
    except RecursionError:
        raise BadMessage("it is nested too deeply to read") from None
    except ValueError as exc:  # JSONDecodeError, and integers of more digits than Python converts
        raise BadMessage(f"it is not JSON ({getattr(exc, 'msg', exc)})") from None
    if _LONE_SURROGATE_ESCAPE.search(text):
        _check_text(msg)
    if may_hold_controls(text):  # terminal control characters are shown, never obeyed (bt_grasp.files.terminal_text)
        try:
            msg = shown_deep(msg)
        except RecursionError:
            raise BadMessage("it is nested too deeply to read") from None
    return msg
