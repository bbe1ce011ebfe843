"""The shapes of bt_grasp's own JSON messages, as ``TypedDict``s: what the recorder writes, and what a log that
``bt_grasp.recording.validate`` checked is known to hold.

The two sides differ on purpose. The writer's side is exact (``TickMessage``: every key this bt_grasp writes,
with its type); the reader's side (``Logged...``) says only what the checks guarantee of any log bt_grasp
reads, older formats and other writers included: a key the checks do not require is ``NotRequired``, a value
they allow to be null is ``| None``, and a key they do not check at all is ``JsonValue`` (read it with a type
check). ``topics.JSON_SCHEMAS`` gives the same shapes to Foxglove.
"""

from __future__ import annotations

from typing import NotRequired, TypedDict

from bt_grasp.files.json_types import JsonObject, JsonValue

# -- what the recorder writes --------------------------------------------------------------------------------


class NodeEntry(TypedDict):
    """One node in a ``/bt/tick`` message: a node ticked, or whose status, feedback or reason changed
    (``jsonable.NodeDiffer``). The keys are written in this order."""

    uid: int
    status: str
    feedback: str
    failure_reason: NotRequired[str]  # left out when None (Foxglove's JSON schemas have no nullable types)
    ticked: bool
    # the first time a uid is written: its names, so a tick stream reads without the tree structure
    path: NotRequired[str]
    type: NotRequired[str]
    name: NotRequired[str]


class TickMessage(TypedDict):
    """``/bt/tick``: one tick."""

    tick: int
    stamp_ns: int
    nodes: list[NodeEntry]
    leaves: dict[str, str]  # every leaf's status, keyed by ``topics.leaf_keys`` of the leaves' paths
    bb: NotRequired[JsonObject]  # the blackboard entries that changed
    bb_removed: NotRequired[list[str]]  # the blackboard entries that went away


# -- what a checked log holds --------------------------------------------------------------------------------


class LoggedNode(TypedDict):
    """One node entry of a checked ``/bt/tick`` message."""

    uid: int
    status: str
    feedback: NotRequired[str | None]
    failure_reason: NotRequired[str | None]
    ticked: NotRequired[bool]
    path: NotRequired[str]
    type: NotRequired[str]
    name: NotRequired[str]
    kind: NotRequired[str]


class LoggedTick(TypedDict):
    """A checked ``/bt/tick`` message."""

    tick: int
    stamp_ns: int
    nodes: NotRequired[list[LoggedNode]]
    bb: NotRequired[JsonObject]
    bb_removed: NotRequired[list[str]]


class LoggedTreeNode(TypedDict):
    """One node of a checked ``/bt/tree`` structure (what ``tree.records.TreeNode`` becomes in a log)."""

    uid: int
    path: NotRequired[str]
    type: NotRequired[str]
    name: NotRequired[str]
    kind: NotRequired[str]
    attributes: NotRequired[JsonObject]
    children: NotRequired[list[LoggedTreeNode]]


class LoggedTree(TypedDict):
    """A checked ``/bt/tree`` message."""

    tick: NotRequired[int | None]
    structure: LoggedTreeNode


class LoggedResult(TypedDict, total=False):
    """A checked ``/run/result`` (``EpisodeResult.to_json``, or ``interrupted_result``): the keys the checks
    cover are typed; the others are read with a type check."""

    success: bool | None
    reason: str | None
    failed_leaf: str | None
    sim_time_s: float | None
    wall_time_s: float | None
    ticks: int | None
    # not checked
    failed_path: JsonValue
    interrupted: JsonValue
    retries: JsonValue
    judge: JsonValue


class LoggedJointState(TypedDict, total=False):
    """A checked ``/robot/joint_state`` message."""

    tick: int | None
    name: list[str]
    position: list[float]
    velocity: list[float]
    gripper_width_m: float | None
    tcp_xyz_m: list[float]
    tcp_quat_xyzw: list[float]


class LoggedWaypoint(TypedDict):
    q_rad: list[float | None]


class LoggedTrajectory(TypedDict, total=False):
    """A checked ``/motion/trajectory`` message (format 1 wrote ``q_rad`` rows, format 2 ``points``), with the
    ``stamp_ns`` the reader adds."""

    stamp_ns: int
    name: JsonValue
    kind: JsonValue
    times_s: list[float | None]
    q_rad: list[list[float | None]]
    points: list[LoggedWaypoint]


class LoggedEvent(TypedDict, total=False):
    """A checked ``/bt/events`` message, with the ``stamp_ns`` the reader adds."""

    tick: int | None
    stamp_ns: int
    kind: JsonValue
    payload: JsonValue


class LoggedFault(TypedDict, total=False):
    """A checked ``/faults`` message, with the ``stamp_ns`` the reader adds."""

    tick: int | None
    stamp_ns: int
    fault: JsonValue


class LoggedIntervention(TypedDict, total=False):
    """A checked ``/control/interventions`` message (``control.InterventionRecord.to_json``)."""

    tick: int | None
    stamp_ns: int
    source: JsonValue
    kind: JsonValue
    command: JsonValue
    effect: JsonValue
