"""Topic names, schema names and the JSON schemas of bt_grasp's own JSON topics.

One place names every channel a bt_grasp log holds, so the writer, the reader and the replay command
agree. Foxglove well-known schemas (protobuf) are named by their full protobuf names.
"""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Sequence

from bt_grasp.files.json_types import JsonObject, JsonValue

#: Metadata record holding the run's description (seed, tree file, versions, ...).
RUN_METADATA_NAME = "bt_grasp.run"
#: Version of the layout of the topics below, in the run metadata as ``log_format``. The reader reads every
#: version in ``READABLE_LOG_FORMATS`` and refuses others with one sentence naming the version.
#: 1: log_time = simulated time from 0, publish_time = wall clock, frames "base"/"camera"/"tool", JSON schemas
#:    Foxglove rejects. 2: log_time = publish_time = run start (wall) + simulated time (metadata
#:    ``time_origin_ns``), URDF frame names, every link on /tf, the robot's meshes, CameraCalibration.
#: 3: ``/bt/tick.leaves`` keyed by each leaf's path (:func:`leaf_key`), no longer by its bare name, and the
#:    Foxglove layout of the tree that ran attached to the log (``foxglove/layout.json``).
#: 4: ``/bt/attempts``: one message per grasp or placement attempt (what, where, how it ended, what it ruled out;
#:    ``bt_grasp.behaviours.attempts``). Nothing else changed: a format-3 log reads as one with no attempts.
LOG_FORMAT_VERSION = "4"
READABLE_LOG_FORMATS: tuple[str, ...] = ("1", "2", "3", "4")
#: metadata key: the wall-clock time (ns since the Unix epoch) at which simulated time 0 is placed
TIME_ORIGIN_KEY = "time_origin_ns"

TREE = "/bt/tree"
TICK = "/bt/tick"
EVENTS = "/bt/events"
#: one message per grasp or placement attempt, written when it ended (bt_grasp.behaviours.attempts)
ATTEMPTS = "/bt/attempts"
FAULTS = "/faults"
RESULT = "/run/result"
JOINT_STATE = "/robot/joint_state"
TRAJECTORY = "/motion/trajectory"
TF = "/tf"
ROBOT_MODEL = "/robot/model"
SCENE = "/scene/fixtures"
COLOR = "/camera/color"
DEPTH = "/camera/depth"
CALIBRATION = "/camera/calibration"
POINTS = "/perception/points"
DETECTIONS = "/perception/detections"
#: the detections drawn on the camera image (the image panel's overlay)
DETECTIONS_2D = "/perception/detections_2d"
GRASPS = "/perception/grasps"
LOG = "/log"
#: the simulator's true object poses, written by the judge's side for offline debugging; nothing in the
#: pipeline reads a log, and nothing reads this topic back into a run
JUDGE_OBJECTS = "/judge/true_objects"
#: an operator's interventions in an interactive run (bt_grasp.control): registered at the first one, so a run
#: without interventions has no such channel
INTERVENTIONS = "/control/interventions"

#: Topics whose messages are JSON objects.
JSON_TOPICS: tuple[str, ...] = (TREE, TICK, EVENTS, FAULTS, RESULT, JOINT_STATE, TRAJECTORY, ATTEMPTS)
#: Topics whose messages are Foxglove protobuf messages, with their schema names.
PROTOBUF_TOPICS: dict[str, str] = {
    TF: "foxglove.FrameTransforms",
    ROBOT_MODEL: "foxglove.SceneUpdate",
    SCENE: "foxglove.SceneUpdate",
    COLOR: "foxglove.CompressedImage",
    DEPTH: "foxglove.RawImage",
    CALIBRATION: "foxglove.CameraCalibration",
    POINTS: "foxglove.PointCloud",
    DETECTIONS: "foxglove.SceneUpdate",
    DETECTIONS_2D: "foxglove.ImageAnnotations",
    GRASPS: "foxglove.SceneUpdate",
    LOG: "foxglove.Log",
    JUDGE_OBJECTS: "foxglove.SceneUpdate",
}
#: Topics the reader loads eagerly (everything except bulky sensor data).
EAGER_TOPICS: tuple[str, ...] = (*JSON_TOPICS, LOG, INTERVENTIONS)
#: JSON topics whose channel is registered when the first message is written (not at the start of a log)
LATE_JSON_TOPICS: tuple[str, ...] = (INTERVENTIONS,)

# Foxglove Studio's JSON-schema support (1.48) accepts a subset of JSON Schema: one "type" per property (no
# type lists: a value that may be absent is left out of the message instead of written as null), "enum" only
# together with "type", no arrays of arrays, and every object with "properties" (free-form objects such as
# the blackboard declare an empty set; Foxglove still shows their keys).
_STATUS: JsonObject = {"type": "string", "enum": ["SUCCESS", "FAILURE", "RUNNING", "IDLE", "SKIPPED"]}
_INT: JsonObject = {"type": "integer"}
_STR: JsonObject = {"type": "string"}
_FLOATS: JsonObject = {"type": "array", "items": {"type": "number"}}
_FREE: JsonObject = {"type": "object", "properties": {}}


def _object(title: str, properties: JsonObject, required: list[JsonValue]) -> JsonObject:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": properties,
        "required": required,
    }


def _node(children: JsonObject | None) -> JsonObject:
    props: JsonObject = {"uid": _INT, "type": _STR, "name": _STR, "path": _STR, "kind": _STR,
                             "attributes": _FREE}
    if children is not None:
        props["children"] = {"type": "array", "items": children}
    return {"type": "object", "properties": props}


JSON_SCHEMAS: dict[str, JsonObject] = {
    # the tree is recursive; the schema names the fields of three levels (deeper levels are still in the data)
    TREE: _object("bt_grasp.TreeStructure", {"tick": _INT, "structure": _node(_node(_node(None)))}, ["structure"]),
    TICK: _object(
        "bt_grasp.Tick",
        {
            "tick": _INT,
            "stamp_ns": _INT,
            "nodes": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "uid": _INT,
                        "path": _STR,
                        "name": _STR,
                        "type": _STR,
                        "status": _STATUS,
                        "feedback": _STR,
                        "failure_reason": _STR,
                        "ticked": {"type": "boolean"},
                    },
                    "required": ["uid", "status"],
                },
            },
            # every leaf's status this tick, keyed by leaf_keys(): what Foxglove's State Transitions plots
            # (``/bt/tick.leaves.Perceive``); tick_schema() lists the tree's leaves here
            "leaves": _FREE,
            "bb": _FREE,
            "bb_removed": {"type": "array", "items": _STR},
        },
        ["tick", "stamp_ns", "nodes"],
    ),
    EVENTS: _object("bt_grasp.Event", {"tick": _INT, "kind": _STR, "payload": _FREE}, ["kind", "payload"]),
    FAULTS: _object("bt_grasp.Fault", {"tick": _INT, "fault": _FREE}, ["fault"]),
    ATTEMPTS: _object(
        "bt_grasp.Attempt",
        {
            "index": _INT,
            "kind": {"type": "string", "enum": ["grasp", "place"]},
            "leaf": _STR,  # the path of the leaf that made it (PlanGrasp for a grasp)
            "tick": _INT,
            "end_tick": _INT,
            "end_leaf": _STR,
            "outcome": {"type": "string",
                        "enum": ["SUCCEEDED", "FAILED", "STALLED", "BLOCKED", "UNFINISHED", "SKIPPED"]},
            "reason": _STR,
            "object": {"type": "object", "properties": {"centroid_m": _FLOATS, "size_m": _FLOATS,
                                                        "yaw_deg": {"type": "number"}, "label": _STR,
                                                        "class_name": _STR, "shape_class": _STR,
                                                        "color_name": _STR}},
            "family": {"type": "string", "enum": ["top", "side", "long_axis", "rim"]},
            "approach": _STR,
            "tcp_xyz_m": _FLOATS,
            "approach_dir": _FLOATS,
            "closing_dir": _FLOATS,
            "T_base_tcp": _FLOATS,  # row-major 4x4
            "width_m": {"type": "number"},
            "moved": {"type": "boolean"},
            "excluded": {"type": "array", "items": {"type": "object", "properties": {
                "what": _STR, "by": _INT, "rule": _STR, "detail": _STR}}},
            "place_pose": _FLOATS,  # x, y, surface z (m), yaw (deg), base frame
            "T_tcp_object": _FLOATS,
            # the release tool poses a placement found blocked before the arm moved (objects: Foxglove takes no
            # arrays of arrays)
            "blocked": {"type": "array", "items": {"type": "object", "properties": {"T_base_tcp": _FLOATS}}},
            "every_turn_blocked": {"type": "boolean"},
        },
        ["index", "kind", "outcome", "object", "family"],
    ),
    RESULT: _object("bt_grasp.RunResult", {"success": {"type": "boolean"}, "reason": _STR,
                                           "failed_leaf": _STR, "ticks": _INT, "sim_time_s": {"type": "number"}},
                    []),
    JOINT_STATE: _object(
        "bt_grasp.JointState",
        {
            "tick": _INT,
            "name": {"type": "array", "items": _STR},
            "position": _FLOATS,
            "velocity": _FLOATS,
            "gripper_width_m": {"type": "number"},
            "tcp_xyz_m": _FLOATS,
            "tcp_quat_xyzw": _FLOATS,
        },
        ["name", "position"],
    ),
    INTERVENTIONS: _object(
        "bt_grasp.Intervention",
        {
            "tick": _INT,  # applied at the boundary after this tick (0: before the first tick)
            "stamp_ns": _INT,
            "source": {"type": "string", "enum": ["terminal", "foxglove", "api", "resim"]},
            "kind": {"type": "string", "enum": ["set_blackboard", "choose_object", "fire_fault", "stop", "restart"]},
            "command": _FREE,  # the command's JSON form (bt_grasp.control.command_to_json)
            "effect": _STR,
        },
        ["tick", "source", "kind", "command"],
    ),
    TRAJECTORY: _object(
        "bt_grasp.JointTrajectory",
        {
            "name": _STR,
            "kind": {"type": "string", "enum": ["planned", "executed"]},
            "times_s": _FLOATS,
            # one object per waypoint (Foxglove accepts no arrays of arrays)
            "points": {"type": "array", "items": {"type": "object",
                                                  "properties": {"t_s": {"type": "number"}, "q_rad": _FLOATS}}},
        },
        ["name", "kind", "times_s", "points"],
    ),
}


def leaf_key(path: str) -> str:
    """A node path as a key of ``/bt/tick.leaves`` (a Foxglove message path names it: letters, digits and
    ``_`` only): ``/`` becomes ``__`` and ``::`` ``_``, so ``PickObject::18/OpenGripper::26`` is
    ``PickObject_18__OpenGripper_26``. The layout's State Transitions rows are labelled with the path itself."""
    key = re.sub(r"[^A-Za-z0-9_]", "_", path.replace("/", "__").replace("::", "_")) or "leaf"
    return "_" + key if key[0].isdigit() else key


def leaf_keys(paths: Sequence[str]) -> list[str]:
    """The keys of ``/bt/tick.leaves`` for the leaves' paths in tree order (:func:`leaf_key`); a key met
    twice (two leaves of one path) is numbered ``_2``, ``_3``, ... (logs of format 1 and 2 keyed by names)."""
    keys: list[str] = []
    seen: dict[str, int] = {}
    for path in paths:
        key = leaf_key(path)
        seen[key] = seen.get(key, 0) + 1
        keys.append(key if seen[key] == 1 else f"{key}_{seen[key]}")
    return keys


def tick_schema(leaf_names: Sequence[str]) -> JsonObject:
    """The /bt/tick schema with the tree's leaves (their paths) declared under ``leaves``."""
    schema = copy.deepcopy(JSON_SCHEMAS[TICK])
    properties = schema["properties"]
    assert isinstance(properties, dict)  # as _object writes it
    properties["leaves"] = {"type": "object", "properties": {key: _STATUS for key in leaf_keys(leaf_names)}}
    return schema


def json_schema_bytes(topic: str, leaf_names: Sequence[str] = ()) -> bytes:
    schema = tick_schema(leaf_names) if topic == TICK and leaf_names else JSON_SCHEMAS[topic]
    return json.dumps(schema, separators=(",", ":")).encode()
