"""Topic names, schema names and the JSON schemas of bt_grasp's own JSON topics.

One place names every channel a bt_grasp log holds, so the writer, the reader and the replay command
agree. Foxglove well-known schemas (protobuf) are named by their full protobuf names.
"""

from __future__ import annotations

import json
from typing import Any

#: Metadata record holding the run's description (seed, tree file, versions, ...).
RUN_METADATA_NAME = "bt_grasp.run"
#: Version of the layout of the topics below; the reader refuses nothing but reports it.
LOG_FORMAT_VERSION = "1"

TREE = "/bt/tree"
TICK = "/bt/tick"
EVENTS = "/bt/events"
FAULTS = "/faults"
RESULT = "/run/result"
JOINT_STATE = "/robot/joint_state"
TRAJECTORY = "/motion/trajectory"
TF = "/tf"
COLOR = "/camera/color"
DEPTH = "/camera/depth"
POINTS = "/perception/points"
DETECTIONS = "/perception/detections"
GRASPS = "/perception/grasps"
LOG = "/log"

#: Topics whose messages are JSON objects.
JSON_TOPICS: tuple[str, ...] = (TREE, TICK, EVENTS, FAULTS, RESULT, JOINT_STATE, TRAJECTORY)
#: Topics whose messages are Foxglove protobuf messages, with their schema names.
PROTOBUF_TOPICS: dict[str, str] = {
    TF: "foxglove.FrameTransforms",
    COLOR: "foxglove.CompressedImage",
    DEPTH: "foxglove.RawImage",
    POINTS: "foxglove.PointCloud",
    DETECTIONS: "foxglove.SceneUpdate",
    GRASPS: "foxglove.SceneUpdate",
    LOG: "foxglove.Log",
}
#: Topics the reader loads eagerly (everything except bulky sensor data).
EAGER_TOPICS: tuple[str, ...] = (*JSON_TOPICS, LOG)

_NODE_STATUS = {"enum": ["SUCCESS", "FAILURE", "RUNNING", "IDLE", "SKIPPED"]}


def _object(title: str, properties: dict[str, Any], required: list[str]) -> dict[str, Any]:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": properties,
        "required": required,
    }


_FLOATS = {"type": "array", "items": {"type": "number"}}

JSON_SCHEMAS: dict[str, dict[str, Any]] = {
    TREE: _object(
        "bt_grasp.TreeStructure",
        {"tick": {"type": ["integer", "null"]}, "structure": {"type": "object"}},
        ["structure"],
    ),
    TICK: _object(
        "bt_grasp.Tick",
        {
            "tick": {"type": "integer"},
            "stamp_ns": {"type": "integer"},
            "nodes": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "uid": {"type": "integer"},
                        "status": _NODE_STATUS,
                        "feedback": {"type": "string"},
                        "failure_reason": {"type": ["string", "null"]},
                        "ticked": {"type": "boolean"},
                    },
                    "required": ["uid", "status"],
                },
            },
            "bb": {"type": "object"},
            "bb_removed": {"type": "array", "items": {"type": "string"}},
        },
        ["tick", "stamp_ns", "nodes"],
    ),
    EVENTS: _object(
        "bt_grasp.Event",
        {"tick": {"type": ["integer", "null"]}, "kind": {"type": "string"}, "payload": {"type": "object"}},
        ["kind", "payload"],
    ),
    FAULTS: _object(
        "bt_grasp.Fault",
        {"tick": {"type": ["integer", "null"]}, "fault": {"type": "object"}},
        ["fault"],
    ),
    RESULT: _object("bt_grasp.RunResult", {"success": {"type": "boolean"}}, []),
    JOINT_STATE: _object(
        "bt_grasp.JointState",
        {
            "tick": {"type": ["integer", "null"]},
            "name": {"type": "array", "items": {"type": "string"}},
            "position": _FLOATS,
            "velocity": _FLOATS,
            "gripper_width_m": {"type": ["number", "null"]},
            "tcp_xyz_m": _FLOATS,
            "tcp_quat_xyzw": _FLOATS,
        },
        ["name", "position"],
    ),
    TRAJECTORY: _object(
        "bt_grasp.JointTrajectory",
        {
            "name": {"type": "string"},
            "kind": {"enum": ["planned", "executed"]},
            "times_s": _FLOATS,
            "q_rad": {"type": "array", "items": _FLOATS},
        },
        ["name", "kind", "times_s", "q_rad"],
    ),
}


def json_schema_bytes(topic: str) -> bytes:
    return json.dumps(JSON_SCHEMAS[topic], separators=(",", ":")).encode()
