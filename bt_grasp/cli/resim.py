"""Re-simulating a recorded run: rebuild it from the log's own attachments and compare tick by tick.

The tree, scene, calibration and fault plan are taken from the log's attachments (the exact bytes the run
used), the seed, blackboard, injections and tick limit from its metadata; the new run is recorded to a
temporary MCAP file and compared with the recorded one by their run fingerprints
(``bt_grasp.recording.fingerprint``: per tick every node's status and failure reason, the blackboard, the
joints to 1e-6 rad and the gripper width; the final object poses), plus the node-status stream comparison
that names the first differing node statuses.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.errors import InputError, LogFileError
from bt_grasp.files.safe_path import check_relative_name, join_under
from bt_grasp.scene.goals import Goal

if TYPE_CHECKING:  # the recording and control packages are imported when a log is re-simulated
    from bt_grasp.control.state import InterventionRecord
    from bt_grasp.episode.request import BlackboardValue
    from bt_grasp.recording.compare import Divergence
    from bt_grasp.recording.fingerprint import FingerprintDifference
    from bt_grasp.recording.reader import RunLog


@dataclass
class ResimReport:
    ticks_recorded: int
    ticks_new: int
    divergence: Divergence | None
    success_recorded: bool | None
    success_new: bool
    new_log: str
    fingerprint_difference: FingerprintDifference | None = None
    digest_recorded: str = ""
    digest_new: str = ""
    #: an interactive run's interventions applied again at their ticks, and the first that was not (a sentence)
    interventions: int = 0
    intervention_difference: str | None = None

    @property
    def reproduced(self) -> bool:
        return (self.divergence is None and self.fingerprint_difference is None
                and self.intervention_difference is None)

    def to_json(self) -> dict[str, object]:
        return {
            "reproduced": self.reproduced,
            "ticks_recorded": self.ticks_recorded,
            "ticks_new": self.ticks_new,
            "success_recorded": self.success_recorded,
            "success_new": self.success_new,
            "first_divergence": asdict(self.divergence) if self.divergence is not None else None,
            "fingerprint": {
                "recorded": self.digest_recorded,
                "new": self.digest_new,
                "first_difference": None if self.fingerprint_difference is None
                else asdict(self.fingerprint_difference),
            },
            "new_log": self.new_log,
            "interventions": {"reapplied": self.interventions, "first_difference": self.intervention_difference},
        }


def _write_attachment(log_path: Path, workdir: Path, name: str, data: bytes) -> Path:
    """Write one attachment under ``workdir`` by its recorded name, through the one name gate: a name with
    ``..``, an absolute name or a link out of the folder is refused (exit 2), never followed."""
    path = join_under(workdir, name, source=log_path, what="attachment name")
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("xb") as f:  # a name recorded twice must not overwrite the first
        f.write(data)
    return path


def _attachment(run: RunLog, folder: str, workdir: Path, log_path: Path) -> Path | None:
    for name, data in run.attachments.items():
        if name.startswith(folder + "/"):
            return _write_attachment(log_path, workdir, name, data)
    return None


def recorded_goal(log_path: Path, meta: dict[str, str]) -> Goal | None:
    """The goal a log was judged against (None for older logs: the scene's goal or the default pick)."""
    if "goal" not in meta:
        return None
    from pydantic import TypeAdapter, ValidationError

    try:
        goal: Goal = TypeAdapter(Goal).validate_json(meta["goal"])
    except ValidationError:
        raise LogFileError(log_path, "the recorded goal cannot be read") from None
    return goal


def resimulate(log_path: Path, keep_log: Path | None = None, leaves: tuple[str, ...] = ()) -> ResimReport:
    """Re-run a recorded log in a temporary folder that is removed afterwards, whatever happens; the new run's
    log is kept only at ``keep_log`` when given. ``leaves``: the ``--leaves`` plugins the run used (a log never
    names code to load by itself: the user passes them again)."""
    from bt_grasp.files.bounded_io import confined_to

    with tempfile.TemporaryDirectory(prefix="bt_grasp_resim_") as tmp, \
            confined_to(Path(tmp), "a log's tree, scene, calibration and fault plan may name only the files the log "
                                   "carries, so this run cannot be re-simulated"):
        try:
            report = _resimulate(log_path, Path(tmp), leaves)
        except InputError as exc:  # a file the log carries, named as the log names it (its folder is gone)
            if exc.source == str(log_path):
                raise
            raise LogFileError(log_path, f"cannot be re-simulated: {_in_log(exc.message, tmp)}") from None
        if keep_log is not None:
            from bt_grasp.files.output_files import copy_output_file

            report.new_log = str(copy_output_file(report.new_log, keep_log, "--resim-log", example="resim.mcap"))
        else:
            report.new_log = ""
    return report


def _in_log(sentence: str, workdir: str) -> str:
    """A sentence about the files of a re-simulation's work folder, with each named as the log names it."""
    sentence = re.sub(re.escape(workdir) + r"/([^\s':,()]*)", lambda m: "the log's " + os.path.normpath(m.group(1)),
                      sentence)
    return sentence.replace(workdir, "the log's files")


def _resimulate(log_path: Path, workdir: Path, leaves: tuple[str, ...] = ()) -> ResimReport:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.compare import compare_tick_streams
    from bt_grasp.recording.fingerprint import fingerprint_of_log
    from bt_grasp.recording.reader import open_log
    from bt_grasp.recording.reproducible import log_epoch_ns

    run = open_log(log_path)
    meta = run.metadata
    if meta.get("ran_on") in ("twin", "robot"):
        where = "a twin" if meta["ran_on"] == "twin" else "a robot"
        raise LogFileError(log_path, f"was recorded on {where} ({meta.get('arm_address', 'a real cell')}) on the "
                           "wall clock: its objects moved in a world no log holds and its time was not simulated, so "
                           "it cannot be re-simulated (replay shows what it recorded)")
    for name in run.attachments:  # a log with any hostile name is refused whole, written or not
        check_relative_name(name, source=log_path, what="attachment name")
    tree_files = [n for n in run.attachments if n.startswith("tree/")]
    if not tree_files or "seed" not in meta:
        raise LogFileError(log_path, "the log has no recorded tree or seed, so the run cannot be re-simulated")
    for name in tree_files:  # every tree file (includes too), in one folder as they were named
        _write_attachment(log_path, workdir, name, run.attachments[name])
    includes = _recorded_include_links(log_path, meta, tree_files, workdir)
    main_name = Path(meta.get("tree_file", tree_files[0])).name
    tree = join_under(workdir / "tree", main_name, source=log_path, what="tree file name")
    scene = _attachment(run, "scene", workdir, log_path)
    if scene is None:
        raise LogFileError(log_path, "the log has no recorded scene file, so the run cannot be re-simulated")
    calibration = _attachment(run, "calibration", workdir, log_path)
    faults = _attachment(run, "faults", workdir, log_path)
    inject = tuple(i for i in meta.get("inject", "").split(";") if i)
    blackboard = _recorded_blackboard(log_path, meta)
    seed = _recorded_int(log_path, meta, "seed", "0", 0, MAX_SEED)
    max_ticks = _recorded_int(log_path, meta, "max_ticks", "12000", 1, MAX_RESIM_TICKS)
    goal = recorded_goal(log_path, meta)
    recorded_leaves = [v for v in meta.get("leaves", "").split(";") if v]
    if recorded_leaves and not leaves:
        raise LogFileError(log_path, f"the run used --leaves {' '.join(recorded_leaves)}; pass them again with "
                           "--leaves (a log never loads code by itself)")
    recorded_interventions = _interventions(log_path, run.interventions)
    latency = _recorded_latency(log_path, meta)
    new_log = workdir / "resim.mcap"
    request = EpisodeRequest(
        tree=tree,
        scene=scene,
        seed=seed,
        goal=goal,
        calibration=calibration,
        log=new_log,
        max_ticks=max_ticks,
        faults=faults,
        inject=inject,
        blackboard=blackboard,
        argv=("bt-grasp", "replay", str(log_path), "--resim"),
        leaves=leaves,
        log_epoch_ns=log_epoch_ns(os.environ),
        perception_latency_s=latency,
    )
    controller = None
    if recorded_interventions:
        from bt_grasp.control import Controller

        controller = Controller(replay=recorded_interventions)
    if includes is None:  # a log from before logs said where each include was found: beside, as it was named
        summary = run_episode(request, controller=controller)
    else:
        from bt_grasp.tree.loader import recorded_includes

        with recorded_includes(includes):
            summary = run_episode(request, controller=controller)
    new_run = open_log(new_log)
    divergence = compare_tick_streams(run.ticks, new_run.ticks, stop_at_shorter=run.truncated)
    recorded_print, new_print = fingerprint_of_log(run), fingerprint_of_log(new_run)
    # a truncated log never reached its end: compare the ticks it has; a log from before final poses were
    # recorded has none: compare the ticks and the run length only
    final_known = bool(recorded_print.final_objects)
    difference = recorded_print.first_difference(new_print, compare_final=not run.truncated)
    if difference is not None and difference.tick is None and not final_known:
        difference = None
    recorded_success = run.result.get("success") if isinstance(run.result, dict) else None
    applied = controller.interventions if controller is not None else ()
    return ResimReport(len(run.ticks), len(new_run.ticks), divergence, recorded_success, summary.success,
                       str(new_log), difference, recorded_print.digest, new_print.digest,
                       len(recorded_interventions), _first_intervention_difference(recorded_interventions, applied))


def _recorded_include_links(log_path: Path, meta: dict[str, str], tree_files: list[str], workdir: Path
                            ) -> dict[tuple[str, str], Path] | None:
    """The run metadata ``tree_includes`` (``[including file, path as written, included file]``, by attachment
    name) as the loader's map: each include resolves to the log's own copy, never to a file of this machine.
    None when the log has no such record (older logs: includes are looked for beside, inside the work folder)."""
    if "tree_includes" not in meta:
        return None
    try:
        rows = json.loads(meta["tree_includes"])
    except (ValueError, RecursionError):
        rows = None
    if not isinstance(rows, list) or not all(
            isinstance(r, list) and len(r) == 3 and all(isinstance(v, str) for v in r) for r in rows):
        raise LogFileError(log_path, "its run metadata 'tree_includes' is not a list of [file, include, file]")
    links: dict[tuple[str, str], Path] = {}
    for source, written, target in rows:
        for name in (source, target):
            if name not in tree_files:
                raise LogFileError(log_path, f"its run metadata 'tree_includes' names {name[:80]!r}, which is not a "
                                   "tree file the log carries")
        including = join_under(workdir, source, source=log_path, what="attachment name")
        links[(os.path.realpath(including), written)] = join_under(workdir, target, source=log_path,
                                                                   what="attachment name")
    return links


#: a recorded seed is a 64-bit integer; a re-simulation runs at most this many ticks (28 simulated hours)
MAX_SEED = 2**63 - 1
MAX_RESIM_TICKS = 10_000_000


def _recorded_int(log_path: Path, meta: dict[str, str], key: str, default: str, low: int, high: int) -> int:
    """An integer of the log's run metadata, from ``low`` to ``high``; anything else is one sentence (exit 2)."""
    text = meta.get(key, default) or default
    if not (text.isascii() and text.isdigit() and len(text) < 20 and low <= int(text) <= high):
        raise LogFileError(log_path, f"its run metadata '{key}' is {text[:40]!r}, not an integer from {low} to {high}")
    return int(text)


#: the longest perception latency a log may name, s (a scene's own limit)
MAX_LATENCY_S = 2.0


def _recorded_latency(log_path: Path, meta: dict[str, str]) -> float:
    """The perception latency the run paid: its metadata's, 0 for a log made before latency was paid (those runs
    handed a capture's detections to the tree in the tick it was taken)."""
    text = meta.get("perception_latency_s", "0") or "0"
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 <= value <= MAX_LATENCY_S:
        raise LogFileError(log_path, f"its run metadata 'perception_latency_s' is {text[:40]!r}, not a number of "
                                     f"seconds from 0 to {MAX_LATENCY_S:g}")
    return value


def _recorded_blackboard(log_path: Path, meta: dict[str, str]) -> dict[str, BlackboardValue]:
    """The blackboard entries the run started with: a JSON object of scalars (as ``--set`` gives them)."""
    try:
        value = json.loads(meta.get("blackboard", "{}") or "{}")
    except (ValueError, RecursionError):
        value = None
    if not isinstance(value, dict) or not all(isinstance(v, str | int | float | bool) for v in value.values()):
        raise LogFileError(log_path, "its run metadata 'blackboard' is not a JSON object of text, numbers and "
                                     "booleans")
    return value


def _interventions(log_path: Path, recorded: Sequence[Mapping[str, object]]) -> list[InterventionRecord]:
    """The log's interventions as records, each command checked; a malformed one is one sentence (exit 2)."""
    from bt_grasp.control import CommandError, InterventionRecord, command_from_json

    records = []
    for index, data in enumerate(recorded):
        try:
            record = InterventionRecord.from_json(data)
            command_from_json(record.command)
        except (KeyError, TypeError, ValueError, CommandError) as exc:
            raise LogFileError(log_path, f"intervention {index} on /control/interventions cannot be applied "
                                         f"again: {exc}") from None
        records.append(record)
    return records


def _first_intervention_difference(recorded: Sequence[InterventionRecord], applied: Sequence[InterventionRecord]
                                   ) -> str | None:
    """Where the re-simulation's interventions differ from the recorded ones (tick, command, effect)."""
    for was, now in zip(recorded, applied, strict=False):
        if (was.tick, was.command, was.effect) != (now.tick, now.command, now.effect):
            return (f"tick {was.tick}: recorded {was.command} ({was.effect}), applied at tick {now.tick}: "
                    f"{now.command} ({now.effect})")
    if len(recorded) != len(applied):
        return f"{len(recorded)} interventions recorded, {len(applied)} applied again"
    return None
