"""The shapes of a campaign's results rows: what a worker writes (``ResultRow``), and what a report knows of a
row that ``results.read_report_rows`` checked (``ReportRow``); a row read without those checks (resuming a
campaign) is JSON (``JsonObject``) with its ``episode`` column.

The keys are the results file's columns (``docs/evaluation.md``): users read them, so they are kept as they are.
"""

from __future__ import annotations

from typing import NotRequired, TypedDict

from bt_grasp.files.json_types import JsonObject, JsonValue


class Environment(TypedDict):
    """What a row was computed with (``environment.environment``); ``id`` is a digest of the rest."""

    code: str
    libraries: dict[str, str]
    python: str
    os: str
    machine: str
    cpu_model: str
    cpu_count: int | None
    vulkan_icd: str
    id: NotRequired[str]


class ResultRow(TypedDict):
    """One finished episode as a worker writes it (``worker.make_row``), in this column order."""

    campaign: str
    episode: str
    index: int
    tree: str
    scene: str
    seed: int
    fault_plan: str
    params: dict[str, str | int | float | bool]
    max_ticks: int
    inputs_digest: str
    success: bool
    judged_goal: str
    tree_status: str
    failure_reason: str | None
    failed_leaf: str | None
    failed_path: str | None
    retries: dict[str, int]
    retries_total: int
    faults_fired: int
    faults: list[JsonObject]  # each firing: label, kind, tick, leaf, target (an object pushed), target_touched
    ticks: int
    sim_time_s: float
    judge: JsonObject
    fingerprint: str
    wall_time_s: float
    setup_wall_s: float
    episode_wall_s: float
    mcap: str | None
    worker: str
    finished_at: str
    environment: Environment


class ReportRow(TypedDict):
    """A row of a results file as ``results.read_report_rows`` checked it: the columns a report reads, typed;
    the others as JSON."""

    episode: str
    tree: str
    scene: str
    fault_plan: str
    seed: int
    success: bool
    failure_reason: str | None
    failed_leaf: str | None
    ticks: int | None
    sim_time_s: float
    episode_wall_s: float
    retries_total: int
    retries: dict[str, int]
    campaign: NotRequired[str]
    mcap: NotRequired[str | None]
    failed_path: NotRequired[str | None]
    params: NotRequired[JsonObject]
    environment: NotRequired[ReportEnvironment | None]
    worker: NotRequired[JsonValue]  # not checked
    faults: NotRequired[JsonValue]  # not checked: each firing's label, kind, tick, leaf, target, target_touched


class ReportEnvironment(TypedDict, total=False):
    """A checked row's ``environment``: only ``libraries`` is checked (an object, or nothing)."""

    libraries: dict[str, JsonValue] | None  # (or another false value: read it with ``or {}``)
    id: JsonValue
    cpu_model: JsonValue
    cpu_count: JsonValue
    python: JsonValue
