"""`bt-grasp replay LOG`: read a recorded run back (summary, one tick, failures, a leaf, a topic, exports).

A log that cannot be read raises ``LogFileError`` (exit code 2, one sentence); replaying a run that failed
is a success (exit code 0).
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import typer
from rich.console import Console
from rich.markup import escape

from bt_grasp.cli.plugin_option import leaves_option

if TYPE_CHECKING:  # the recording package (mcap, cv2) is imported when a log is replayed, not for --help
    from bt_grasp.recording.attempt_view import AttemptRow
    from bt_grasp.recording.reader import RunLog
    from bt_grasp.recording.replay import FailureReport, StatusChange
    from bt_grasp.recording.replay_shapes import LeafState, TickView


class _Views(TypedDict, total=False):
    """The views asked for, as JSON: one tick, the failures, a leaf's history, the attempts."""

    tick: TickView
    failures: list[dict[str, object]]
    leaf: list[LeafState]
    attempts: list[AttemptRow]


def _json(console: Console, value: object) -> None:
    console.out(json.dumps(value, indent=2, default=str), highlight=False)


def replay_command(
    log: Path = typer.Argument(..., help="The run's .mcap log file."),
    tick: int | None = typer.Option(None, "--tick", help="Show the tree, blackboard and arm at tick N."),
    failures: bool = typer.Option(False, "--failures", help="List every FAILURE and what ran next."),
    leaf: str | None = typer.Option(None, "--leaf", help="Status history of the node with this name."),
    attempts: bool = typer.Option(False, "--attempts", help="Every grasp and placement attempt: where, how it ended, "
                                  "what earlier attempts ruled out before it, and whether it repeats a failed one."),
    topic: str | None = typer.Option(None, "--topic", help="Print a topic's messages as JSON lines."),
    as_json: bool = typer.Option(False, "--json", help="Machine-readable output."),
    frames_dir: Path | None = typer.Option(None, "--export-frames", help="Write images as PNG here."),
    btlog: Path | None = typer.Option(None, "--export-btlog", help="Write a Groot2 .btlog file."),
    max_rows: int = typer.Option(200, "--max-rows", min=1, help="Rows shown in the timeline and histories."),
    resim: bool = typer.Option(
        False, "--resim", help="Re-run the recorded tree, scene, seed, calibration and faults; compare every tick."
    ),
    resim_log: Path | None = typer.Option(
        None, "--resim-log", help="With --resim: keep the re-simulated run's log here (else it is removed)."
    ),
    report: Path | None = typer.Option(None, "--report", help="Write a self-contained HTML run report here."),
    report_dir: Path | None = typer.Option(None, "--report-dir", help="Also write the report's figures as PNG here."),
    foxglove: bool = typer.Option(
        False, "--foxglove",
        help="Write the Foxglove layout of this log's tree (LOG.layout.json) and say how to open both."
    ),
    layout_out: Path | None = typer.Option(
        None, "--layout-out", help="With --foxglove: write the layout here instead of beside the log."
    ),
    leaves: list[str] = leaves_option(),
) -> None:
    """Replay a recorded run: summary and timeline by default, or the views asked for."""
    from bt_grasp.recording import render, replay
    from bt_grasp.recording.btlog import write_btlog
    from bt_grasp.recording.export import export_frames
    from bt_grasp.recording.reader import open_log

    console = Console(highlight=False)
    _check_outputs(log, report, report_dir, btlog, frames_dir, layout_out, resim_log)  # before any work
    run = open_log(log)
    if resim:
        _resim(console, log, as_json, resim_log, tuple(leaves))
        return
    if foxglove:
        _print_foxglove(console, run, layout_out)
    if report is not None or report_dir is not None:
        from bt_grasp.recording.report import build_report

        html_path = report if report is not None else report_dir / "report.html"  # type: ignore[operator]
        made = build_report(run, html_path, report_dir, repeated=_repeated(run))
        console.print(f"wrote the run report {escape(str(made.html_path))}"
                      + (f" and {len(made.pngs)} figures to {escape(str(report_dir))}" if made.pngs else ""))
    other_views = tick is not None or failures or leaf or attempts or topic or as_json or frames_dir or btlog
    if (foxglove or report is not None or report_dir is not None) and not other_views:
        return
    views: _Views = {}
    if tick is not None:
        views["tick"] = replay.tick_view(run, tick)
    if failures:
        views["failures"] = [
            {**_asdict(f), "recovery": [_asdict(c) for c in f.recovery]} for f in replay.failures(run)
        ]
    if leaf is not None:
        views["leaf"] = replay.leaf_history(run, leaf)
    if attempts:
        from bt_grasp.recording.attempt_view import attempt_rows

        views["attempts"] = attempt_rows(run.attempts, _repeated(run))
    exports: dict[str, object] = {}
    if frames_dir is not None:
        frames = [str(p) for p in export_frames(run, frames_dir)]
        exports["frames"] = frames
    if btlog is not None:
        written = write_btlog(run, btlog)
        exports["btlog"] = {"path": str(btlog), "transitions": len(written.transitions)}

    if topic is not None:
        for message in replay.topic_messages(run, topic):
            console.out(json.dumps(message, separators=(",", ":"), default=str), highlight=False)
    if as_json:
        if not views and topic is None:
            _json(console, {**replay.summary(run), **({"exports": exports} if exports else {})})
        elif len(views) == 1 and not exports:
            _json(console, next(iter(views.values())))
        elif views or exports:
            _json(console, {**views, **({"exports": exports} if exports else {})})
        return
    if not views and topic is None and not exports:
        console.print(render.summary_table(replay.summary(run)))
        console.print()
        console.print(render.timeline_table(replay.timeline(run), max_rows, replay.fault_marks(run)))
        if run.interventions:
            from bt_grasp.recording.interventions import interventions_table

            console.print()
            console.print(interventions_table(run.interventions))
    _print_views(console, run.path.name, views, leaf, max_rows, run)
    if frames_dir is not None:
        console.print(f"wrote {len(frames)} frames to {escape(str(frames_dir))}")
    if btlog is not None:
        console.print(f"wrote {len(written.transitions)} transitions to {escape(str(btlog))}")


def _repeated(run: RunLog) -> set[int]:
    """The numbers of the run's attempts that repeat a failed earlier one (issue 46's rules)."""
    from bt_grasp.behaviours.attempts import repeats

    return {later for _, later in repeats([a for a in run.attempts if a.get("outcome") != "SKIPPED"])}


def _print_foxglove(console: Console, run: RunLog, target: Path | None) -> None:
    from bt_grasp.foxglove.tree_layout import write_layout

    origin = run.time_origin_ns
    layout = write_layout(run, target)  # the layout of this log's tree (attached to the log since format 3)
    console.print(
        f"Open {escape(str(run.path))} in Foxglove (desktop or app.foxglove.dev: Open local file, or drag the file "
        f"in).\nThen load the layout made for this run's tree: Layouts > Import from file > {escape(str(layout))}\n"
        "It shows the arm, point cloud, detections and grasps in 3D, the camera with detections drawn, each "
        "leaf's status over time (State Transitions: one row per leaf of this tree, named by its path), joint "
        "and gripper plots and the log.\n"
        + (f"The timeline starts at the run's real start ({_utc(origin)}); simulated time runs on from there."
           if origin else "This log is format 1: its timeline starts at 1970-01-01 (simulated time from 0)."),
        soft_wrap=True,  # paths stay whole, to be copied
    )


def _utc(ns: int) -> str:
    import datetime

    return datetime.datetime.fromtimestamp(ns / 1e9, datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def _resim(console: Console, log: Path, as_json: bool, keep: Path | None, leaves: tuple[str, ...] = ()) -> None:
    from bt_grasp.cli.resim import resimulate

    report = resimulate(log, keep, leaves)
    if as_json:
        _json(console, report.to_json())
    elif report.reproduced:
        console.print(
            f"[green]reproduced[/]: {report.ticks_new} ticks, the same fingerprint (every node's status and "
            f"reason, blackboard, joints, gripper at every tick; final object poses) {report.digest_new[:16]} "
            f"(success {report.success_new})" + (f"; new log {escape(report.new_log)}" if report.new_log else "")
            + (f"; {report.interventions} interventions applied again at their ticks" if report.interventions
               else "")
        )
    else:
        d = report.divergence
        if d is not None:
            console.print(f"[red]diverged[/] at tick {d.tick} ({d.kind}); recorded {report.ticks_recorded} "
                          f"ticks, new {report.ticks_new}")
            for diff in d.differences[:20]:
                console.print(f"  {escape(str(diff))}")
        if report.fingerprint_difference is not None:
            console.print(f"[red]fingerprints differ[/]: {escape(report.fingerprint_difference.describe())}")
        if report.intervention_difference is not None:
            console.print(f"[red]interventions differ[/]: {escape(report.intervention_difference)}")
    if not report.reproduced:
        raise typer.Exit(1)


def _check_outputs(log: Path, report: Path | None, report_dir: Path | None, btlog: Path | None,
                   frames_dir: Path | None, layout_out: Path | None, resim_log: Path | None) -> None:
    """Every place the command will write, checked before the log is read (``bt_grasp.files.output_files``)."""
    from bt_grasp.files.output_files import check_output_file, check_output_folder

    files = ((report, "--report", "report.html"), (btlog, "--export-btlog", "run.btlog"),
             (layout_out, "--layout-out", "run.layout.json"), (resim_log, "--resim-log", "resim.mcap"))
    for path, flag, example in files:
        if path is not None:
            check_output_file(path, flag, example=example, inputs=(log,))
    for folder, flag in ((report_dir, "--report-dir"), (frames_dir, "--export-frames")):
        if folder is not None:
            check_output_folder(folder, flag)


def _asdict(obj: FailureReport | StatusChange) -> dict[str, object]:
    return {k: v for k, v in asdict(obj).items() if k != "recovery"}


def _print_views(
    console: Console, name: str, views: _Views, leaf: str | None, max_rows: int, run: RunLog
) -> None:
    from bt_grasp.recording import render, replay

    if "tick" in views:
        view = views["tick"]
        stamp = view["stamp_ns"] * 1e-9 if view["stamp_ns"] is not None else float("nan")
        console.print(render.tree_render(view["tree"], f"{name} at tick {view['tick']} ({stamp:.3f} s)"))
        for fault in view["faults"]:  # injected faults that fired in this tick
            console.print(render.fault_text(replay.FaultMark(**fault)))
        console.print(render.mapping_table("blackboard", view["blackboard"]))
        console.print(render.robot_table(view["robot"]))
    if "failures" in views:
        console.print(render.failures_table(replay.failures(run)))
    if "leaf" in views and leaf is not None:
        console.print(render.leaf_table(leaf, views["leaf"], max_rows))
    if "attempts" in views:
        from bt_grasp.recording.attempt_view import attempts_table

        rows = views["attempts"]
        if not rows:
            console.print("no grasp or placement attempt recorded (a log written before /bt/attempts, log format "
                          "4, has none: `bt-grasp bench attempts LOG` rebuilds its grasps)")
        else:
            console.print(attempts_table(rows))
            repeats = [r["index"] for r in rows if r["repeats"]]
            console.print(f"{len(rows)} attempt(s); " + (f"repeating a failed one: {repeats}" if repeats
                                                        else "none repeats a failed one"))


def register(app: typer.Typer) -> None:
    app.command("replay")(replay_command)
