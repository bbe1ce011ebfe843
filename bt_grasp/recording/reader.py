"""`open_log(path) -> RunLog`: a bt_grasp MCAP log as typed Python records.

Everything but the bulky sensor topics is loaded at open (ticks, tree structures, events, faults, logs,
trajectories, result); images and point clouds are read on demand. A finished file is read through its
index; a file with no summary (a killed run) or cut short is read linearly and flagged ``truncated``.
Anything that is not a readable bt_grasp log raises ``LogFileError`` (exit code 2 at the command line).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple, TypeAlias, TypedDict, TypeVar

import cv2
import numpy as np
from google.protobuf.json_format import MessageToDict
from google.protobuf.message import Message
from numpy.typing import NDArray

from bt_grasp.errors import LogFileError
from bt_grasp.files.image_header import MAX_IMAGE_SIDE, image_size
from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.files.terminal_text import shown
from bt_grasp.recording import mcap_io, topics, validate
from bt_grasp.recording.messages import (
    LoggedEvent,
    LoggedFault,
    LoggedIntervention,
    LoggedJointState,
    LoggedResult,
    LoggedTick,
    LoggedTrajectory,
    LoggedTreeNode,
)
from bt_grasp.recording.schemas import PROTOBUF_CLASSES
from bt_grasp.recording.validate import BadMessage, is_int, parse_json
from bt_grasp.tree.registry import NodeKind

log = logging.getLogger(__name__)

#: a decoded message: JSON for bt_grasp's own topics, a protobuf message for Foxglove's
Decoded: TypeAlias = JsonValue | Message
#: a colour image (HxWx3 uint8 RGB) or a depth image (HxW uint16 mm or float32 m): ``Image.kind`` says which
Pixels: TypeAlias = NDArray[np.uint8 | np.uint16 | np.float32]
_T = TypeVar("_T")

#: leaf kinds as the tree introspection writes them (``NodeKind.value``: "Action", "Condition")
LEAF_KINDS = frozenset({NodeKind.ACTION.value, NodeKind.CONDITION.value})


class NodeUpdate(NamedTuple):
    """A node's state as written for one tick (only nodes ticked or changed that tick are written).

    A NamedTuple, not a dataclass: a long log holds hundreds of thousands and they are built at open.
    """

    uid: int
    status: str
    feedback: str = ""
    failure_reason: str | None = None
    ticked: bool = False


class LogLine(TypedDict):
    """A /log message as the reader keeps it."""

    stamp_ns: int
    level: str
    name: str
    message: str


@dataclass(frozen=True)
class TickRecord:
    tick: int
    stamp_ns: int
    nodes: tuple[NodeUpdate, ...]
    bb: JsonObject
    bb_removed: tuple[str, ...] = ()


@dataclass(frozen=True)
class NodeInfo:
    uid: int
    path: str
    type: str
    name: str
    kind: str = ""
    parent: int | None = None
    depth: int = 0

    @property
    def is_leaf(self) -> bool:
        return self.kind in LEAF_KINDS

    @property
    def label(self) -> str:
        return self.name if self.name and self.name == self.type else f"{self.name} ({self.type})"


@dataclass(frozen=True)
class TreeSnapshot:
    """The tree's structure as written on /bt/tree (``tick``: the last tick written before it, or None)."""

    stamp_ns: int
    tick: int | None
    root: LoggedTreeNode

    def nodes(self) -> dict[int, NodeInfo]:
        out: dict[int, NodeInfo] = {}
        stack: list[tuple[LoggedTreeNode, int | None, int]] = [(self.root, None, 0)]
        while stack:
            node, parent, depth = stack.pop()
            uid = int(node["uid"])
            out[uid] = NodeInfo(uid, str(node.get("path", "")), str(node.get("type", "")),
                                str(node.get("name", "")), str(node.get("kind", "")), parent, depth)
            stack.extend((child, uid, depth + 1) for child in reversed(node.get("children", [])))
        return out


@dataclass(frozen=True)
class TopicMessage:
    topic: str
    log_time_ns: int
    publish_time_ns: int
    schema_name: str
    message: Decoded  # JSON for JSON topics, a protobuf message for Foxglove topics


@dataclass(frozen=True)
class Image:
    topic: str
    stamp_ns: int
    frame_id: str
    kind: str  # "color" (HxWx3 uint8 RGB) or "depth" (HxW uint16 mm or float32 m)
    encoding: str
    pixels: Pixels


@dataclass
class RunLog:
    """One recorded run. ``ticks`` are in tick order; ``truncated`` says the file was not finished."""

    path: Path
    metadata: dict[str, str]
    attachments: dict[str, bytes]
    structures: list[TreeSnapshot]
    ticks: list[TickRecord]
    events: list[LoggedEvent]
    faults: list[LoggedFault]
    logs: list[LogLine]
    trajectories: list[LoggedTrajectory]
    result: LoggedResult | None
    topics: dict[str, int]
    truncated: bool
    indexed: bool
    library: str = ""
    stop_reason: str = ""
    _learned: dict[int, NodeInfo] = field(default_factory=dict, repr=False)
    #: stamp_ns -> the /robot/joint_state message, decoded (and checked) when asked for
    _robot_raw: dict[int, mcap_io.RawMessage] = field(default_factory=dict, repr=False)
    #: the file's time of simulated time 0 (format 2; 0 for format 1, whose times are simulated time)
    time_origin_ns: int = 0
    #: an interactive run's interventions (/control/interventions), each with its ``stamp_ns``
    interventions: list[LoggedIntervention] = field(default_factory=list)
    #: the run's grasp and placement attempts (/bt/attempts; log format 4), each with its ``stamp_ns``
    attempts: list[JsonObject] = field(default_factory=list)

    @property
    def ticks_recovered(self) -> int:
        return len(self.ticks)

    @property
    def nodes(self) -> dict[int, NodeInfo]:
        """uid -> node, from the last tree structure, completed by names written with the first tick."""
        merged = dict(self._learned)
        if self.structures:
            merged.update(self.structures[-1].nodes())
        return merged

    def structure_at(self, tick: int) -> TreeSnapshot | None:
        chosen = self.structures[0] if self.structures else None
        for snap in self.structures:
            if snap.tick is None or snap.tick < tick:
                chosen = snap
        return chosen

    def tick_record(self, tick: int) -> TickRecord | None:
        for record in self.ticks:
            if record.tick == tick:
                return record
        return None

    def states_at(self, tick: int) -> dict[int, NodeUpdate]:
        """Every node's last written state at the end of ``tick``."""
        states: dict[int, NodeUpdate] = {}
        for record in self.ticks:
            if record.tick > tick:
                break
            for node in record.nodes:
                states[node.uid] = node
        return states

    def blackboard_at(self, tick: int) -> JsonObject:
        board: JsonObject = {}
        for record in self.ticks:
            if record.tick > tick:
                break
            board.update(record.bb)
            for key in record.bb_removed:
                board.pop(key, None)
        return board

    def robot_at(self, tick: int) -> LoggedJointState | None:
        """The last arm state (/robot/joint_state) written at or before ``tick``."""
        for record in reversed(self.ticks):
            if record.tick <= tick and record.stamp_ns in self._robot_raw:
                return _json_at(self.path, self._robot_raw[record.stamp_ns], self.time_origin_ns,
                                validate.joint_state_message)
        return None

    def joint_states(self) -> Iterator[tuple[int, LoggedJointState]]:
        """(simulated time, message) of every /robot/joint_state message, decoded and checked."""
        for raw in mcap_io.iter_topic(self.path, [topics.JOINT_STATE], self.indexed):
            yield (raw.log_time_ns - self.time_origin_ns,
                   _json_at(self.path, raw, self.time_origin_ns, validate.joint_state_message))

    def protobuf_messages(self, topic: str) -> Iterator[tuple[int, Message]]:
        """(simulated time, message) of every message on one of Foxglove's topics (``topics.PROTOBUF_TOPICS``)."""
        if topic not in topics.PROTOBUF_TOPICS:
            raise ValueError(f"{topic} is not a protobuf topic")
        for raw in mcap_io.iter_topic(self.path, [topic], self.indexed):
            yield raw.log_time_ns - self.time_origin_ns, _protobuf_at(self.path, raw, self.time_origin_ns)

    def iter_messages(self, topic: str) -> Iterator[TopicMessage]:
        """Every message on ``topic``, decoded (JSON -> dict, Foxglove -> protobuf message) and checked."""
        for raw in mcap_io.iter_topic(self.path, [topic], self.indexed):
            yield TopicMessage(raw.topic, raw.log_time_ns - self.time_origin_ns, raw.publish_time_ns,
                               raw.schema_name, decode_at(self.path, raw, self.time_origin_ns))

    def images(self) -> Iterator[Image]:
        """The recorded colour and depth images, decoded to numpy arrays, in file order; an image that does
        not decode is a ``LogFileError`` naming its topic and time (it is bad input, found when shown)."""
        for raw in mcap_io.iter_topic(self.path, [topics.COLOR, topics.DEPTH], self.indexed):
            msg = _protobuf_at(self.path, raw, self.time_origin_ns)
            stamp = raw.log_time_ns - self.time_origin_ns
            try:
                yield _image(raw.topic, msg, msg.timestamp.seconds * 1_000_000_000 + msg.timestamp.nanos
                             - self.time_origin_ns)
            except BadMessage as exc:
                raise LogFileError(self.path, f"has a bad image on {raw.topic} at {stamp} ns: {exc}") from None


_DEPTH_TYPES: dict[str, np.dtype[np.uint16 | np.float32]] = {"16UC1": np.dtype("<u2"), "32FC1": np.dtype("<f4")}


def _image(topic: str, msg: Message, stamp: int) -> Image:
    if topic == topics.COLOR:
        size = image_size(msg.data)
        if size is None:
            raise BadMessage(f"its data ({len(msg.data)} bytes) is not a PNG or JPEG image")
        if not (0 < size[0] <= MAX_IMAGE_SIDE and 0 < size[1] <= MAX_IMAGE_SIDE):
            raise BadMessage(f"it says it is {size[0]} x {size[1]} pixels, more than a camera's {MAX_IMAGE_SIDE} "
                             "a side")
        bgr = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
        if bgr is None:
            raise BadMessage(f"its {msg.format or 'unnamed'} data ({len(msg.data)} bytes) does not decode")
        rgb: NDArray[np.uint8] = np.asarray(bgr[:, :, ::-1], dtype=np.uint8).copy()
        return Image(topic, stamp, msg.frame_id, "color", msg.format, rgb)
    dtype = _DEPTH_TYPES.get(msg.encoding)
    if dtype is None:
        raise BadMessage(f"its encoding {msg.encoding!r} is not one of {', '.join(_DEPTH_TYPES)}")
    row_items = len(msg.data) // dtype.itemsize // msg.height if msg.height else 0
    if not msg.width or row_items < msg.width or len(msg.data) != row_items * msg.height * dtype.itemsize:
        raise BadMessage(f"its {len(msg.data)} bytes are not {msg.height} rows of {msg.width} {msg.encoding} pixels")
    pixels = np.frombuffer(msg.data, dtype=dtype).reshape(msg.height, row_items)[:, : msg.width]
    return Image(topic, stamp, msg.frame_id, "depth", msg.encoding, pixels.copy())


def _check_encoding(raw: mcap_io.RawMessage) -> None:
    """A topic bt_grasp writes must come in the encoding and schema it writes; raises ``BadMessage``."""
    if raw.topic in topics.JSON_TOPICS and raw.message_encoding != "json":
        raise BadMessage(f"its encoding is {raw.message_encoding!r}, not 'json'")
    expected = topics.PROTOBUF_TOPICS.get(raw.topic)
    if expected is not None and (raw.message_encoding, raw.schema_name) != ("protobuf", expected):
        raise BadMessage(f"it is {raw.message_encoding!r} of schema {raw.schema_name!r}, not 'protobuf' of "
                         f"{expected!r}")


def decode(raw: mcap_io.RawMessage) -> Decoded:
    """One message: JSON (checked: :mod:`bt_grasp.recording.validate`) or a Foxglove protobuf message; a topic
    bt_grasp writes must come in the encoding and schema it writes; raises ``BadMessage``."""
    _check_encoding(raw)
    if raw.message_encoding == "json":
        return parse_json(raw.topic, raw.data)
    cls = PROTOBUF_CLASSES.get(raw.schema_name)
    if raw.message_encoding == "protobuf" and cls is not None:
        msg: Message = cls()
        try:
            msg.ParseFromString(raw.data)
        except Exception as exc:  # protobuf's DecodeError, or a RecursionError on hostile nesting
            raise BadMessage(f"it is not a {raw.schema_name} message ({type(exc).__name__})") from None
        return msg
    return {"__undecoded__": {"encoding": raw.message_encoding, "schema": raw.schema_name,
                              "bytes": len(raw.data)}}


def _bad_message(path: Path, raw: mcap_io.RawMessage, origin: int, exc: BadMessage) -> LogFileError:
    return LogFileError(path, f"has a bad message on {raw.topic} at {raw.log_time_ns - origin} ns: {exc}")


def decode_at(path: Path, raw: mcap_io.RawMessage, origin: int) -> Decoded:
    """``decode``, with a message that does not decode as one sentence naming the file, topic and time."""
    try:
        return decode(raw)
    except BadMessage as exc:
        raise _bad_message(path, raw, origin, exc) from None


def _protobuf_at(path: Path, raw: mcap_io.RawMessage, origin: int) -> Message:
    """A message of one of Foxglove's topics (``topics.PROTOBUF_TOPICS``): ``decode_at`` refuses any other
    encoding or schema on those."""
    msg = decode_at(path, raw, origin)
    if not isinstance(msg, Message):
        raise _bad_message(path, raw, origin, BadMessage("it is not a protobuf message"))
    return msg


def _json_at(path: Path, raw: mcap_io.RawMessage, origin: int, check: Callable[[JsonValue], _T]) -> _T:
    """One of bt_grasp's own JSON messages, checked by ``check`` (``validate.tick_message``, ...) and typed as
    what it checked; a message that is not one is one sentence naming the file, topic and time."""
    try:
        _check_encoding(raw)
        return check(validate.json_value(raw.data))
    except BadMessage as exc:
        raise _bad_message(path, raw, origin, exc) from None


def message_to_jsonable(message: Decoded) -> JsonValue:
    """A decoded message as JSON-able data; bulky ``data`` fields of images and clouds become their size."""
    if not isinstance(message, Message):
        return message
    out: JsonObject = MessageToDict(message, preserving_proto_field_name=True)
    if "data" in out:
        out["data"] = {"__bytes__": len(message.data)}
    return out


def _tick_record(msg: LoggedTick) -> TickRecord:
    nodes = tuple(
        NodeUpdate(int(n["uid"]), str(n["status"]), str(n.get("feedback") or ""), n.get("failure_reason"),
                   bool(n.get("ticked", False)))
        for n in msg.get("nodes", [])
    )
    tick = int(msg["tick"])
    return TickRecord(tick, int(msg["stamp_ns"]), nodes, dict(msg.get("bb", {})),
                      tuple(msg.get("bb_removed", [])))


def _not_bt_grasp(path: Path, scan: mcap_io.Scan, size: int) -> LogFileError | None:
    if not scan.header_seen:
        return LogFileError(path, f"is cut off after {size} bytes, before the end of its MCAP header")
    if topics.RUN_METADATA_NAME in scan.metadata or topics.TICK in scan.topic_counts:
        return None
    if not scan.complete:
        return LogFileError(path, f"is cut off after {size} bytes, before its bt_grasp run metadata")
    name = topics.RUN_METADATA_NAME
    return LogFileError(path, f"is an MCAP file but not a bt_grasp log (no '{name}' metadata)")


def open_log(path: str | Path) -> RunLog:
    """Open a bt_grasp log; raises ``LogFileError`` for anything that is not one."""
    p = Path(path)
    scan = mcap_io.scan_file(p, topics.EAGER_TOPICS)
    problem = _not_bt_grasp(p, scan, p.stat().st_size)
    if problem is not None:
        raise problem
    metadata = {shown(k): shown(v) for k, v in scan.metadata.get(topics.RUN_METADATA_NAME, {}).items()}
    fmt = metadata.get("log_format", "1")
    if fmt not in topics.READABLE_LOG_FORMATS:
        readable = " and ".join(topics.READABLE_LOG_FORMATS)
        printed = fmt if fmt.isascii() and fmt.isprintable() and len(fmt) <= 20 else repr(fmt[:20])
        raise LogFileError(p, f"was written in bt_grasp log format {printed}; this bt_grasp reads formats {readable}")
    origin = _time_origin(p, metadata)  # format 1: simulated time from 0
    robot_raw: dict[int, mcap_io.RawMessage] = {}
    tick_messages: list[LoggedTick] = []
    structures: list[TreeSnapshot] = []
    events: list[LoggedEvent] = []
    faults: list[LoggedFault] = []
    trajectories: list[LoggedTrajectory] = []
    results: list[LoggedResult] = []
    logs: list[LogLine] = []
    interventions: list[LoggedIntervention] = []
    attempts: list[JsonObject] = []
    for raw in scan.messages:  # every message but the arm states is decoded and checked once, here, in file order
        topic, stamp = raw.topic, raw.log_time_ns - origin
        if topic == topics.JOINT_STATE:  # one per tick: decoded and checked only when one is shown
            robot_raw[stamp] = raw
        elif topic == topics.TICK:
            tick_messages.append(_json_at(p, raw, origin, validate.tick_message))
        elif topic == topics.TREE:
            tree = _json_at(p, raw, origin, validate.tree_message)
            structures.append(TreeSnapshot(stamp, tree.get("tick"), tree["structure"]))
        elif topic == topics.EVENTS:
            events.append({"stamp_ns": stamp, **_json_at(p, raw, origin, validate.event_message)})
        elif topic == topics.FAULTS:
            faults.append({"stamp_ns": stamp, **_json_at(p, raw, origin, validate.fault_message)})
        elif topic == topics.ATTEMPTS:
            attempts.append({"stamp_ns": stamp, **_json_at(p, raw, origin, validate.attempt_message)})
        elif topic == topics.TRAJECTORY:
            trajectories.append(_trajectory({"stamp_ns": stamp,
                                             **_json_at(p, raw, origin, validate.trajectory_message)}))
        elif topic == topics.RESULT:
            results.append(_json_at(p, raw, origin, validate.result_message))
        elif topic == topics.INTERVENTIONS:  # a late JSON topic: decoded as any topic is, then checked
            interventions.append({"stamp_ns": stamp, **_intervention_at(p, raw, origin)})
        else:
            msg = decode_at(p, raw, origin)
            if topic == topics.LOG and isinstance(msg, Message):
                logs.append({"stamp_ns": stamp, "level": _level_name(msg), "name": shown(msg.name),
                             "message": shown(msg.message)})
    learned: dict[int, NodeInfo] = {}
    ticks = []
    for msg in tick_messages:
        ticks.append(_tick_record(msg))
        for n in msg.get("nodes", []):
            uid = int(n["uid"])
            if "path" in n and uid not in learned:
                learned[uid] = NodeInfo(uid, n["path"], n.get("type", ""), n.get("name", ""))
    ticks.sort(key=lambda t: t.tick)
    return RunLog(
        path=p,
        metadata=metadata,
        attachments=scan.attachments,
        structures=structures,
        ticks=ticks,
        events=events,
        faults=faults,
        logs=logs,
        trajectories=trajectories,
        result=results[-1] if results else None,
        topics=dict(sorted((shown(topic), n) for topic, n in scan.topic_counts.items())),
        truncated=not scan.complete,
        indexed=scan.indexed,
        library=scan.library,
        stop_reason=scan.stop_reason,
        _learned=learned,
        _robot_raw=robot_raw,
        time_origin_ns=origin,
        interventions=interventions,
        attempts=attempts,
    )


def _intervention_at(path: Path, raw: mcap_io.RawMessage, origin: int) -> LoggedIntervention:
    msg = decode_at(path, raw, origin)
    try:
        return validate.intervention_message(msg)
    except BadMessage as exc:
        raise _bad_message(path, raw, origin, exc) from None


def _time_origin(path: Path, metadata: dict[str, str]) -> int:
    text = metadata.get(topics.TIME_ORIGIN_KEY, "0") or "0"
    value = int(text) if text.isascii() and text.isdigit() and len(text) < 20 else None
    if value is None or not is_int(value):
        raise LogFileError(path, f"its run metadata '{topics.TIME_ORIGIN_KEY}' is {text[:40]!r}, not a time in "
                                 "nanoseconds")
    return value


def _level_name(msg: Message) -> str:
    try:
        return str(msg.Level.Name(msg.level))
    except ValueError:  # a level number the schema does not name
        return str(msg.level)


def _trajectory(msg: LoggedTrajectory) -> LoggedTrajectory:
    """Format 2 writes waypoints as objects; readers get ``q_rad`` rows as format 1 wrote them."""
    if "q_rad" not in msg and "points" in msg:
        msg = {**msg, "q_rad": [p["q_rad"] for p in msg["points"]]}
    return msg
