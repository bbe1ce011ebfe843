"""The shapes of what ``bt-grasp replay`` shows as data (``replay.py`` computes them; ``render.py``, the run
report and ``--json`` show them). The keys are the ``--json`` output's: a user's script may read them."""

from __future__ import annotations

from typing import TypedDict

from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.recording.messages import LoggedIntervention, LoggedJointState, LoggedResult


class ReplaySummary(TypedDict):
    """``replay.summary``: the run at a glance."""

    file: str
    tree: str
    scene: str
    seed: int | None  # MCAP metadata is text: the seed is a number here
    fault_plan: str
    success: bool | None
    interrupted: bool  # Ctrl-C ended the run (success is null)
    reason: str | None
    failed_leaf: str | None
    failed_path: JsonValue
    ticks: int
    first_tick: int | None
    last_tick: int | None
    sim_duration_s: float
    retries: JsonValue  # the result's, else counted from the tick stream
    retries_per_leaf: dict[str, int]
    failures_per_leaf: dict[str, int]  # not the ones false by design:
    false_by_design_per_leaf: dict[str, int]  # conditions asked, ForceFailure
    truncated: bool
    ticks_recovered: int
    result: LoggedResult | None
    topics: dict[str, int]
    faults: list[dict[str, object]]
    interventions: list[LoggedIntervention]
    events: int
    metadata: dict[str, str]
    attachments: list[str]


class LeafState(TypedDict):
    """``replay.leaf_history``: one written state of a node."""

    tick: int
    stamp_ns: int
    uid: int
    status: str
    feedback: str
    failure_reason: str | None
    ticked: bool
    name: str


class AnnotatedNode(TypedDict):
    """``replay.tree_at``: a node of the recorded structure with its state at one tick."""

    uid: int
    name: str
    type: str
    kind: str
    path: str
    status: str
    feedback: str
    failure_reason: str | None
    ticked: bool
    children: list[AnnotatedNode]


class FaultMarkJson(TypedDict):
    """``replay.FaultMark`` as JSON (its fields, in their order)."""

    tick: int
    stamp_ns: int
    label: str
    kind: str
    target: str
    effect: str


class TickView(TypedDict):
    """``replay.tick_view``: everything recorded of one tick."""

    tick: int
    stamp_ns: int | None
    tree: AnnotatedNode
    blackboard: JsonObject
    robot: LoggedJointState | None
    faults: list[FaultMarkJson]  # the faults that fired in this tick


class TopicRecord(TypedDict):
    """``replay.topic_messages``: one message of a topic as JSON."""

    topic: str
    log_time_ns: int
    publish_time_ns: int
    message: JsonValue
