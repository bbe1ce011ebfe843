"""`RunRecorder`: one crash-tolerant, indexed MCAP file per run, readable by `bt-grasp replay` and Foxglove.

Usage (the runner owns the loop; the recorder only writes)::

    with RunRecorder(path, metadata={...}, attachments={"tree.xml": xml_bytes}) as rec:
        rec.write_tree_structure(0, structure)
        for tick in ...:
            rec.write_tick(tick, stamp_ns, nodes, blackboard, robot)
            ...                      # images, markers, events, faults of this tick
            rec.flush_tick()         # ends the chunk: a killed process keeps everything up to here
        rec.write_result(stamp_ns, result)

Callers pass simulated time (``stamp_ns``, from 0 at the start of the run). In the file every time is
``time_origin_ns + stamp_ns``: ``log_time``, ``publish_time`` and the Foxglove messages' own timestamps, with
``time_origin_ns`` the wall clock at the start of the run (metadata ``time_origin_ns``). So Foxglove's timeline
shows the date of the run and simulated time runs on from there; the file depends on the wall clock in that one
number only, and nothing in a run reads it (docs/recording.md argues the convention).
Chunks are compressed (zstd by default) and indexed; ``close()`` (or leaving the ``with`` block, also
through an exception, Ctrl-C or SIGTERM) writes the summary and footer. Not thread-safe: one thread writes.
"""

from __future__ import annotations

import functools
import logging
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as dist_version
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, BinaryIO, Literal

import cv2
import numpy as np
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer
from mcap_protobuf.schema import build_file_descriptor_set
from numpy.typing import ArrayLike, NDArray

from bt_grasp.files.json_types import JsonValue
from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.recording import schemas, topics
from bt_grasp.recording.arm_state import ArmStateEncoder
from bt_grasp.recording.arm_state import ticked as _ticked
from bt_grasp.recording.encodings import Encoding, encode
from bt_grasp.recording.jsonable import BlackboardDiffer, NodeDiffer, to_jsonable
from bt_grasp.recording.messages import NodeEntry, TickMessage
from bt_grasp.recording.projection import box_corners_px
from bt_grasp.recording.signals import SignalGuard
from bt_grasp.recording.tf_encoding import FrameTransformsEncoder
from bt_grasp.recording.writer_process import ArmSettings, ProcessWriter

if TYPE_CHECKING:
    from bt_grasp.recording.robot_model import RobotModel
    from bt_grasp.tree.records import NodeRecord, TreeNode

log = logging.getLogger(__name__)

#: frame ids: the robot description's link names and the calibration file's camera frame
WORLD_FRAME = "world"
BASE_FRAME = "base_link"
TOOL_FRAME = "tcp"
CAMERA_FRAME = "camera_color_optical_frame"
UR5_JOINT_NAMES: tuple[str, ...] = (
    "shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
    "wrist_1_joint", "wrist_2_joint", "wrist_3_joint",
)
_LEAF_KINDS = ("Action", "Condition")  # NodeKind values of leaves
#: how a log's chunks are compressed
Compression = Literal["zstd", "lz4", "none"]
_COMPRESSION = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
_MEDIA_TYPES = {".xml": "application/xml", ".yaml": "application/yaml", ".yml": "application/yaml",
                ".json": "application/json", ".txt": "text/plain", ".urdf": "application/xml"}


@functools.cache
def _library_id() -> str:
    """The MCAP header's library: read from the installed packages' metadata once per process (~5 ms each time
    it was read, once per log)."""
    try:
        ours = dist_version("bt-grasp")
    except PackageNotFoundError:
        ours = "0"
    return f"bt_grasp/{ours}; mcap-python/{dist_version('mcap')}"


def _media_type(name: str, data: bytes) -> str:
    media = _MEDIA_TYPES.get(Path(name).suffix.lower())
    if media:
        return media
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return "application/octet-stream"
    return "text/plain"


@dataclass(frozen=True)
class ChannelSpec:
    """One topic as registered: what a live server advertises so viewers decode it like the file."""

    topic: str
    message_encoding: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes


class RunRecorder:
    """Writes one run to one MCAP file. See the module docstring for the call order.

    Args:
        path: the .mcap file to create (its folder must exist; an existing file is replaced); None writes no
            file (a live stream only: messages still go to the taps, see ``add_tap``).
        metadata: the run's description, written as the MCAP Metadata record ``bt_grasp.run``: seed,
            command line, tree and scene file names, versions, git commit, fault plan, tick rate. Values are
            strings; two keys are added: ``log_format`` and ``start_unix_ns``.
        attachments: file name -> exact bytes of every file needed to run again (tree, scene, calibration,
            fault plan).
        wall_clock: wall time in ns: read once for ``time_origin_ns`` (unless given) and for attachment times.
        time_origin_ns: where simulated time 0 is placed on the file's time line (default: now).
        compression: "zstd", "lz4" or "none" for the chunks.
        chunk_size: a chunk is also ended when it grows past this many bytes.
        image_format: "jpeg" or "png" for /camera/color; jpeg_quality: 0-100.
        depth_encoding: "16UC1" (millimetres) or "32FC1" (metres) for /camera/depth.
        fsync_interval_s: at a ``flush_tick`` at least this long after the last one, also fsync (survives a
            power loss, not only a killed process); None never fsyncs before ``close``.
        flush_every_ticks: 1 ends a chunk at every ``flush_tick``; N > 1 at every Nth (fewer, larger chunks;
            a killed process loses at most the last N - 1 ticks). Counted in ticks, never in wall time, so
            where chunks end, and so the file's bytes, do not depend on the machine's speed.
        handle_signals: while used as a context manager, turn SIGTERM/SIGINT into exceptions that unwind
            through ``__exit__`` (only where those signals still have their default handlers).
        base_frame, tool_frame: frame ids of the arm base and the tool (TCP) on /tf: the robot description's
            link names.
        joint_names: names on /robot/joint_state.
        max_array_elements: blackboard arrays larger than this are logged as a summary, not element-wise.
        leaf_names: the tree's leaves' paths in uid order, declared in the /bt/tick schema so Foxglove can
            plot ``/bt/tick.leaves.<leaf_key(path)>`` (``topics.leaf_key``).
        robot_model: a :class:`bt_grasp.recording.robot_model.RobotModel`: every link's pose goes on /tf with
            each arm state (write its link entities with ``write_scene(ROBOT_MODEL, 0, robot_model_update())``);
            None writes only the tool frame.
        writer_process: write the file from a child process (``writer_process.py``): the tick loop only
            hands data over, and the arm state of a tick with no viewer watching is encoded there too (the
            same bytes). With ``robot_model``, the child builds the default robot model (the one
            ``default_robot_model()`` returns). A file log only; ignored without ``path``.
    """

    def __init__(
        self,
        path: str | Path | None,
        *,
        metadata: Mapping[str, str],
        attachments: Mapping[str, bytes] | None = None,
        wall_clock: Callable[[], int] = time.time_ns,
        compression: Compression = "zstd",
        chunk_size: int = 4 * 1024 * 1024,
        image_format: Literal["jpeg", "png"] = "jpeg",
        jpeg_quality: int = 90,
        depth_encoding: Literal["16UC1", "32FC1"] = "16UC1",
        fsync_interval_s: float | None = None,
        flush_every_ticks: int = 1,
        handle_signals: bool = True,
        time_origin_ns: int | None = None,
        base_frame: str = BASE_FRAME,
        tool_frame: str = TOOL_FRAME,
        joint_names: Sequence[str] = UR5_JOINT_NAMES,
        max_array_elements: int = 64,
        robot_model: RobotModel | None = None,
        leaf_names: Sequence[str] = (),
        writer_process: bool = False,
    ) -> None:
        if compression not in _COMPRESSION:
            raise ValueError(f"unknown compression {compression!r}; expected one of {sorted(_COMPRESSION)}")
        self.to_file = path is not None
        self.path = Path(path) if path is not None else Path(os.devnull)
        self._wall_clock = wall_clock
        self.time_origin_ns = int(wall_clock() if time_origin_ns is None else time_origin_ns)
        self._image_format = image_format
        self._jpeg_quality = jpeg_quality
        self._depth_encoding = depth_encoding
        self._fsync_interval_s = fsync_interval_s
        if flush_every_ticks < 1:
            raise ValueError(f"flush_every_ticks must be >= 1, got {flush_every_ticks}")
        self._flush_every_ticks = int(flush_every_ticks)
        self._ticks_since_flush = 0
        self._last_fsync = time.monotonic()
        self._handle_signals = handle_signals
        self.base_frame = base_frame
        self.tool_frame = tool_frame
        self._joint_names = list(joint_names)
        self._nodes = NodeDiffer()
        self._blackboard = BlackboardDiffer(max_array_elements)
        self._guard = SignalGuard()
        self._last_structure: JsonValue | None = None
        self._last_tick: int | None = None
        self._last_stamp_ns = 0
        self._sequence: dict[int, int] = {}
        self._closed = False
        self._camera_K: NDArray[np.float64] | None = None  # the last camera calibration written
        self._tf_encoder = FrameTransformsEncoder()
        self._arm = ArmStateEncoder(self._joint_names, base_frame, tool_frame, robot_model)
        self._taps: list[Callable[[str, int, bytes], None]] = []
        self._demand: list[Callable[[], bool]] = []
        self._when_watched: dict[str, Callable[[], None]] = {}
        #: called with (kind, payload) after every event written (a failure, a retry, an abort)
        self.event_listeners: list[Callable[[str, Mapping[str, object]], None]] = []
        #: called with the spec of a channel registered mid-run (``late_channel_spec``): a live server advertises it
        self.channel_listeners: list[Callable[[ChannelSpec], None]] = []
        self._robot_model = robot_model
        self._leaf_names = tuple(leaf_names)
        # the leaves' statuses as the last tick wrote them (``_leaf_statuses``)
        self._node_count = -1
        self._leaf_uids: set[int] = set()
        self._leaf_of_uid: dict[int, str] = {}
        self._leaf_status: dict[str, str] = {}
        #: (parent, child) -> T_parent_child repeated in every /tf message written with an arm state, so a
        #: viewer that seeks (and reads only the last /tf message) still has the whole frame tree
        self.static_transforms: dict[tuple[str, str], NDArray[np.float64]] = {}

        self._process: ProcessWriter | None = None
        self._sent_statics: dict[tuple[str, str], int] = {}
        self._file: BinaryIO | None = None
        if writer_process and self.to_file:
            arm: ArmSettings = {"joint_names": self._joint_names, "base_frame": base_frame,
                                "tool_frame": tool_frame, "robot_model": robot_model is not None}
            self._process = ProcessWriter(str(self.path), chunk_size=chunk_size, compression=compression,
                                          arm_state=arm)
            self._writer: Writer | ProcessWriter = self._process
        else:
            self._file = open(self.path, "wb")  # noqa: SIM115 - closed in close()
            self._writer = Writer(self._file, chunk_size=chunk_size, compression=_COMPRESSION[compression])
        try:
            self._start(metadata, attachments or {})
        except BaseException:
            if self._file is not None:
                self._file.close()
            raise

    def _start(self, metadata: Mapping[str, str], attachments: Mapping[str, bytes]) -> None:
        self._writer.start(profile="", library=_library_id())
        meta = {str(k): str(v) for k, v in metadata.items()}
        meta.setdefault("log_format", topics.LOG_FORMAT_VERSION)
        meta.setdefault("start_unix_ns", str(self.time_origin_ns))
        meta[topics.TIME_ORIGIN_KEY] = str(self.time_origin_ns)
        self._writer.add_metadata(topics.RUN_METADATA_NAME, meta)
        now = self._wall_clock()
        for name, data in attachments.items():
            self._writer.add_attachment(now, 0, name, _media_type(name, bytes(data)), bytes(data))
        self._channels: dict[str, int] = {}
        self._register_channels()
        if self._file is not None:
            self._file.flush()
        else:
            self._writer.flush()

    # -- set-up ------------------------------------------------------------------------------------------

    def channel_specs(self) -> list[ChannelSpec]:
        """Every topic with its message encoding and schema, exactly as registered in the file."""
        specs = [ChannelSpec(topic, MessageEncoding.JSON, str(topics.JSON_SCHEMAS[topic]["title"]),
                             SchemaEncoding.JSONSchema, topics.json_schema_bytes(topic, self._leaf_names))
                 for topic in topics.JSON_TOPICS]
        descriptors: dict[str, bytes] = {}
        for topic, schema_name in topics.PROTOBUF_TOPICS.items():
            if schema_name not in descriptors:
                descriptors[schema_name] = build_file_descriptor_set(
                    schemas.PROTOBUF_CLASSES[schema_name]).SerializeToString()
            specs.append(ChannelSpec(topic, MessageEncoding.Protobuf, schema_name, SchemaEncoding.Protobuf,
                                     descriptors[schema_name]))
        return specs

    def _register_channels(self) -> None:
        schema_ids: dict[str, int] = {}
        for spec in self.channel_specs():
            if spec.schema_name not in schema_ids:
                schema_ids[spec.schema_name] = self._writer.register_schema(
                    name=spec.schema_name, encoding=spec.schema_encoding, data=spec.schema_data)
            self._channels[spec.topic] = self._writer.register_channel(
                spec.topic, spec.message_encoding, schema_ids[spec.schema_name])

    def __enter__(self) -> RunRecorder:
        if self._handle_signals:
            self._guard.install()
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self._guard.acknowledge()
        if exc is not None and not self._closed:
            try:
                stamp = self._last_stamp_ns
                self.write_event(stamp, "aborted", {"exception": exc_type.__name__ if exc_type else "",
                                                    "message": str(exc)})
            except Exception:  # the file must still be finished
                log.exception("could not record the abort event")
        self.close()

    # -- low level ---------------------------------------------------------------------------------------

    def _next(self, topic: str, stamp_ns: int) -> tuple[int, int, int]:
        """(channel, sequence number, file time) of the next message on ``topic`` at ``stamp_ns``."""
        if self._closed:
            raise ValueError(f"{self.path}: the recorder is closed")
        channel = self._channels[topic]
        seq = self._sequence.get(channel, 0) + 1
        self._sequence[channel] = seq
        stamp_ns = int(stamp_ns)
        if stamp_ns > self._last_stamp_ns:
            self._last_stamp_ns = stamp_ns
        return channel, seq, self.time_origin_ns + stamp_ns

    def _write(self, topic: str, stamp_ns: int, data: bytes) -> None:
        channel, seq, t = self._next(topic, stamp_ns)
        with self._guard.busy():
            self._writer.add_message(channel, log_time=t, data=data, publish_time=t, sequence=seq)
        for tap in self._taps:
            tap(topic, t, data)

    def add_tap(self, tap: Callable[[str, int, bytes], None], wanted: Callable[[], bool] | None = None) -> None:
        """Also hand every message written to ``tap(topic, time_ns, data)`` (a live server); it must not
        block and must not raise. ``wanted()`` says whether anyone receives the tap's messages now: a recorder
        with no file and no tap wanted skips the per-tick work (see ``active``)."""
        self._taps.append(tap)
        self._demand.append(wanted if wanted is not None else (lambda: True))

    def when_watched(self, key: str, write: Callable[[], None]) -> None:
        """Keep ``write`` (the latest one per ``key``) for the first tick a viewer watches: a frame captured
        while nobody watched is sent then, so a viewer that joins mid-run still sees the last picture."""
        self._when_watched[key] = write

    @property
    def active(self) -> bool:
        """Whether per-tick data (ticks, arm states, images, clouds) reaches anyone: a file, or a viewer."""
        return self.to_file or any(wanted() for wanted in self._demand)

    def t(self, stamp_ns: int) -> int:
        """The file's time of simulated time ``stamp_ns``."""
        return self.time_origin_ns + int(stamp_ns)

    def _write_encoded(self, topic: str, stamp_ns: int, encoding: Encoding, args: tuple[object, ...]) -> None:
        """A message given by its inputs: with a writer process and no live viewer the child encodes it (off
        the tick loop's thread); else it is encoded here. The same bytes either way (``encodings.py``)."""
        if self._process is not None and not self._taps:
            channel, seq, t = self._next(topic, stamp_ns)
            with self._guard.busy():
                self._process.add_encoded(channel, t, seq, encoding, args)
            return
        self._write(topic, stamp_ns, encode(encoding, args))

    def _write_json(self, topic: str, stamp_ns: int, obj: object) -> None:
        """``obj`` as compact JSON; ``obj`` must not be changed afterwards (a writer process encodes it at the
        tick's end)."""
        self._write_encoded(topic, stamp_ns, Encoding.JSON, (obj,))

    # -- the tree ----------------------------------------------------------------------------------------

    def write_tree_structure(self, stamp_ns: int, structure: TreeNode) -> bool:
        """Write the tree's structure on /bt/tree unless it equals the last one written; True if written.

        ``structure``: the root node as nested dicts with ``uid``, ``type``, ``name``, ``path``, ``kind``
        (a ``NodeKind`` value: "Control", "Decorator", "Action", "Condition", "SubTree"), ``attributes`` and
        ``children``.
        """
        converted = to_jsonable(structure, max_array_elements=1 << 30)
        if converted == self._last_structure:
            return False
        self._last_structure = converted
        self._node_count = -1  # another tree: the next tick reads its leaves afresh
        self._write_json(topics.TREE, stamp_ns, _ticked(self._last_tick, {"structure": converted}))
        return True

    def write_tick(
        self,
        tick: int,
        stamp_ns: int,
        nodes: Sequence[NodeRecord],
        blackboard: Mapping[str, object],
        robot: Mapping[str, object] | None = None,
    ) -> None:
        """Record one tick: the nodes ticked or changed, the blackboard entries changed, the arm state.

        ``nodes``: every node of the tree (``tree.records.NodeRecord``, as the runner hands them over).
        ``blackboard``: the full current blackboard. ``robot``:
        ``{"q_rad": [6], "qd_rad_s": [6], "gripper_width_m": float, "T_base_tcp": 4x4}`` or None.
        """
        if not self.active:  # a live view nobody watches: the next watched tick is written in full
            self._last_tick = int(tick)
            self._nodes.reset()
            self._blackboard = BlackboardDiffer(self._blackboard._max)
            return
        if self._when_watched:  # what was captured while nobody watched
            pending, self._when_watched = self._when_watched, {}
            for write in pending.values():
                write()
        changed_nodes = self._nodes.diff(nodes)
        bb_changed, bb_removed = self._blackboard.diff(blackboard)
        msg: TickMessage = {"tick": int(tick), "stamp_ns": int(stamp_ns), "nodes": changed_nodes,
                            "leaves": self._leaf_statuses(nodes, changed_nodes)}
        if bb_changed:
            msg["bb"] = bb_changed
        if bb_removed:
            msg["bb_removed"] = bb_removed
        self._last_tick = int(tick)
        self._write_json(topics.TICK, stamp_ns, msg)
        if robot is not None:
            self.write_robot_state(stamp_ns, robot)

    def _leaf_statuses(
        self, nodes: Sequence[NodeRecord], changed: Sequence[NodeEntry]
    ) -> dict[str, str]:
        """Every leaf's status this tick, keyed by ``topics.leaf_keys`` of the leaves' paths, in uid order.

        A leaf's status changes only in a node entry ``NodeDiffer`` writes (it writes every node whose status
        changed), so the statuses are kept between ticks and updated from this tick's entries; they are read
        from ``nodes`` again only when the nodes are not the ones seen before (another count, or an entry
        for a uid never seen)."""
        known = self._leaf_uids
        if len(nodes) != self._node_count or any(entry["uid"] not in known for entry in changed):
            leaves = [n for n in nodes if n.get("kind") in _LEAF_KINDS]
            names = tuple(str(n.get("path") or n.get("name", "")) for n in leaves)  # keyed by path (format 3)
            keys = topics.leaf_keys(names)
            self._leaf_status = {k: n["status"] for k, n in zip(keys, leaves, strict=True)}
            self._leaf_of_uid = {int(n["uid"]): k for k, n in zip(keys, leaves, strict=True)}
            self._leaf_uids = {int(n["uid"]) for n in nodes}
            self._node_count = len(nodes)
        else:
            leaf_of_uid, status = self._leaf_of_uid, self._leaf_status
            for entry in changed:
                key = leaf_of_uid.get(entry["uid"])
                if key is not None:
                    status[key] = entry["status"]
        return dict(self._leaf_status)

    def write_robot_state(self, stamp_ns: int, robot: Mapping[str, object]) -> None:
        """The arm state on /robot/joint_state (JSON, for plots) and base->tool on /tf (for the 3D view)."""
        if not self.active or "q_rad" not in robot:  # nobody watches, or a state read while nobody did
            return
        if self._process is not None and not self._taps:  # a file only: the writer process encodes it
            self._hand_over_arm_state(stamp_ns, robot)
            return
        joint_state, tf = self._arm.encode(self.t(stamp_ns), self._last_tick, robot, self.static_transforms)
        self._write(topics.JOINT_STATE, stamp_ns, joint_state)
        if tf is not None:
            self._write(topics.TF, stamp_ns, tf)

    def _hand_over_arm_state(self, stamp_ns: int, robot: Mapping[str, object]) -> None:
        assert self._process is not None
        js_channel, js_seq, t = self._next(topics.JOINT_STATE, stamp_ns)
        tf_channel, tf_seq, _ = self._next(topics.TF, stamp_ns)
        statics = {key: id(T) for key, T in self.static_transforms.items()}
        if statics != self._sent_statics:
            self._process.set_statics(self.static_transforms)
            self._sent_statics = statics
        self._process.add_arm_state((js_channel, tf_channel), (js_seq, tf_seq), t, self._last_tick, robot)

    # -- sensors and perception ----------------------------------------------------------------------------

    def write_color_image(self, stamp_ns: int, rgb: NDArray[np.uint8], frame_id: str) -> None:
        schemas.check_color_image(rgb, self._image_format)
        self._write_encoded(topics.COLOR, stamp_ns, Encoding.COLOR,
                            (self.t(stamp_ns), np.array(rgb), frame_id, self._image_format, self._jpeg_quality))

    def write_camera_calibration(self, stamp_ns: int, frame_id: str, intrinsics: CameraIntrinsics) -> None:
        i = intrinsics
        msg = schemas.camera_calibration(self.t(stamp_ns), frame_id, i.width_px, i.height_px, i.fx_px, i.fy_px,
                                         i.cx_px, i.cy_px)
        self._camera_K = np.array(msg.K, dtype=np.float64).reshape(3, 3)
        self._write(topics.CALIBRATION, stamp_ns, msg.SerializeToString())

    def robot_model_update(self) -> SceneUpdate:
        """The robot's link entities (a ``foxglove.SceneUpdate``) at the start of the run."""
        if self._robot_model is None:
            raise ValueError("this recorder has no robot model")
        update: SceneUpdate = self._robot_model.scene_update(self.t(0))
        return update

    def write_scene(self, topic: str, stamp_ns: int, update: SceneUpdate) -> None:
        """A ready ``foxglove.SceneUpdate`` on one of the scene topics (robot model, fixtures, judge)."""
        if topics.PROTOBUF_TOPICS.get(topic) != "foxglove.SceneUpdate":
            raise ValueError(f"{topic!r} is not a scene topic")
        self._write(topic, stamp_ns, update.SerializeToString())

    def write_depth(self, stamp_ns: int, depth_m: NDArray[np.floating], frame_id: str) -> None:
        schemas.check_depth_image(depth_m, self._depth_encoding)
        self._write_encoded(topics.DEPTH, stamp_ns, Encoding.DEPTH,
                            (self.t(stamp_ns), np.array(depth_m), frame_id, self._depth_encoding))

    def write_points(
        self, stamp_ns: int, xyz: ArrayLike, rgb: ArrayLike | None = None, frame_id: str | None = None
    ) -> None:
        msg = schemas.point_cloud(self.t(stamp_ns), xyz, rgb, frame_id or self.base_frame)
        self._write(topics.POINTS, stamp_ns, msg.SerializeToString())

    def write_transforms(self, stamp_ns: int, transforms: Sequence[tuple[str, str, ArrayLike]]) -> None:
        """(parent, child, T_parent_child) triples on /tf, e.g. ("base", "camera", T_base_camera)."""
        self._write(topics.TF, stamp_ns, self._tf_encoder.encode(self.t(stamp_ns), [
            (parent, child, schemas.as_matrix(T)) for parent, child, T in transforms]))

    def write_markers(
        self,
        stamp_ns: int,
        entities: Sequence[schemas.BoxMarker | schemas.PoseMarker],
        *,
        topic: str | None = None,
        frame_id: str | None = None,
    ) -> None:
        """Boxes go to /perception/detections and poses to /perception/grasps, each update replacing the
        markers shown before on its topic. With ``topic`` given, everything goes there (an empty list clears
        it)."""
        frame = frame_id or self.base_frame
        by_topic: dict[str, list[SceneEntity]] = {topic: []} if topic else {}
        for marker in entities:
            if isinstance(marker, schemas.BoxMarker):
                entity, default = schemas.box_entity(self.t(stamp_ns), marker, frame), topics.DETECTIONS
            elif isinstance(marker, schemas.PoseMarker):
                entity, default = schemas.pose_entity(self.t(stamp_ns), marker, frame), topics.GRASPS
            else:
                raise TypeError(f"a marker must be a BoxMarker or a PoseMarker, got {type(marker).__name__}")
            by_topic.setdefault(topic or default, []).append(entity)
        for name, group in by_topic.items():
            if name not in (topics.DETECTIONS, topics.GRASPS):
                raise ValueError(f"markers go to {topics.DETECTIONS} or {topics.GRASPS}, not {name!r}")
            self._write(name, stamp_ns, schemas.scene_update(self.t(stamp_ns), group).SerializeToString())
        boxes = [m for m in entities if isinstance(m, schemas.BoxMarker)]
        if (topic or topics.DETECTIONS) == topics.DETECTIONS:
            self._write_box_outlines(stamp_ns, boxes)

    def _write_box_outlines(self, stamp_ns: int, boxes: Sequence[schemas.BoxMarker]) -> None:
        """The boxes drawn on the camera image, where the camera's calibration and pose are known."""
        T_base_camera = self.static_transforms.get((self.base_frame, CAMERA_FRAME))
        if self._camera_K is None or T_base_camera is None:
            return
        T_camera_base = np.linalg.inv(T_base_camera)
        outlines = []
        for box in boxes:
            corners = box_corners_px(T_camera_base, self._camera_K, schemas.as_matrix(box.T_base_box), box.size_m)
            if corners is not None:
                hull = cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2)
                outlines.append((hull.astype(np.float64), box.label))
        msg = schemas.image_annotations(self.t(stamp_ns), outlines)
        self._write(topics.DETECTIONS_2D, stamp_ns, msg.SerializeToString())

    # -- motion, logs, events ------------------------------------------------------------------------------

    def write_trajectory(
        self, stamp_ns: int, name: str, times_s: ArrayLike, q_rad: ArrayLike,
        kind: Literal["planned", "executed"] = "planned",
    ) -> None:
        if not self.active:  # a live view nobody watches (not latched: a later viewer needs no old motion)
            return
        times = np.array(times_s, dtype=np.float64).ravel()  # copies: the caller may reuse its arrays
        q = np.array(q_rad, dtype=np.float64).reshape(times.size, -1)
        self._write_encoded(topics.TRAJECTORY, stamp_ns, Encoding.TRAJECTORY, (name, kind, times, q))

    def write_log(self, stamp_ns: int, level: str | int, name: str, message: str) -> None:
        self._write(topics.LOG, stamp_ns, schemas.log(self.t(stamp_ns), level, name, message).SerializeToString())

    def write_event(self, stamp_ns: int, kind: str, payload: Mapping[str, object]) -> None:
        """An event on /bt/events (a failure, a retry, an abort); tagged with the last tick written."""
        self._write_json(topics.EVENTS, stamp_ns,
                         _ticked(self._last_tick, {"kind": kind, "payload": to_jsonable(payload)}))
        for listener in self.event_listeners:
            listener(kind, payload)

    def write_attempt(self, stamp_ns: int, attempt: Mapping[str, object]) -> None:
        """One grasp or placement attempt that ended, on /bt/attempts (``Attempt.to_json`` of
        ``bt_grasp.behaviours.attempts``)."""
        self._write_json(topics.ATTEMPTS, stamp_ns, to_jsonable(attempt))

    def write_fault(self, stamp_ns: int, tick: int, fault: Mapping[str, object]) -> None:
        """One firing of an injected fault on /faults."""
        self._write_json(topics.FAULTS, stamp_ns, {"tick": int(tick), "fault": to_jsonable(fault)})

    def write_intervention(self, stamp_ns: int, record: Mapping[str, object]) -> None:
        """An operator's intervention on /control/interventions (``bt_grasp.control.InterventionRecord``); the
        channel is registered with the first one, so a run with none records nothing extra."""
        topic = topics.INTERVENTIONS
        if topic not in self._channels:
            with self._guard.busy():
                schema_id = self._writer.register_schema(
                    name=str(topics.JSON_SCHEMAS[topic]["title"]), encoding=SchemaEncoding.JSONSchema,
                    data=topics.json_schema_bytes(topic))
                self._channels[topic] = self._writer.register_channel(topic, MessageEncoding.JSON, schema_id)
            for listener in self.channel_listeners:
                listener(self.late_channel_spec(topic))
        self._write_json(topic, stamp_ns, to_jsonable(record))

    def late_channel_spec(self, topic: str) -> ChannelSpec:
        """A channel registered only when first written (``topics.LATE_JSON_TOPICS``)."""
        return ChannelSpec(topic, MessageEncoding.JSON, str(topics.JSON_SCHEMAS[topic]["title"]),
                           SchemaEncoding.JSONSchema, topics.json_schema_bytes(topic))

    def write_result(self, stamp_ns: int, result: Mapping[str, object]) -> None:
        """The run's outcome on /run/result: success, reason, failed_leaf, ticks, sim_time_s, wall_time_s,
        retries, object_lift_m, ..."""
        self._write_json(topics.RESULT, stamp_ns, to_jsonable(result))

    # -- durability ------------------------------------------------------------------------------------------

    def flush_tick(self) -> None:
        """At a tick boundary: end the open chunk and hand it to the OS, so a process killed after this
        loses nothing before it. With ``flush_every_ticks`` = N > 1 this happens at every Nth call only (a kill
        then loses at most the N - 1 ticks since). Also fsyncs when
        ``fsync_interval_s`` has passed since the last fsync."""
        if self._closed:
            return
        self._ticks_since_flush += 1
        if self._ticks_since_flush < self._flush_every_ticks:
            return
        self._ticks_since_flush = 0
        fsync = False
        if self._fsync_interval_s is not None:
            now = time.monotonic()
            if now - self._last_fsync >= self._fsync_interval_s:
                fsync = self.to_file
                self._last_fsync = now
        with self._guard.busy():
            if self._process is not None:
                self._process.flush(fsync=fsync)
                return
            self._writer.flush()
        if fsync and self._file is not None:
            os.fsync(self._file.fileno())

    def close(self) -> None:
        """Write the summary (indexes, statistics) and footer, fsync and close. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            with self._guard.busy():
                if self._process is not None:
                    self._process.finish(fsync=True)
                else:
                    assert self._file is not None
                    self._writer.finish()
                    self._file.flush()
                    if self.to_file:
                        os.fsync(self._file.fileno())
        finally:
            if self._file is not None:
                self._file.close()
            self._guard.uninstall()
        log.debug("closed %s", self.path)

    @property
    def closed(self) -> bool:
        return self._closed
