"""`bt-grasp run TREE --cell CELL`: the same tree files on a real cell (a UR through ur_rtde and a RealSense), or on a
twin of one (``docs/real-cell.md``). Parsing and printing only: the run is ``bt_grasp.episode.cell_run``."""

from __future__ import annotations

import json
import signal
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.markup import escape

from bt_grasp.errors import InputError

if TYPE_CHECKING:
    from bt_grasp.episode.cell_run import CellRunRequest, CellRunResult
    from bt_grasp.tree.runner import FailureEvent


def refuse_simulator_options(given: Mapping[str, bool]) -> None:
    """Options that only a simulated run has (faults injected into the simulator, pacing, viewers of a simulated
    run, the resident process) are one sentence with ``--cell``."""
    named = [name for name, on in given.items() if on]
    if named:
        raise InputError(named[0], f"is for a run on the simulator; a run on a real cell (--cell) takes none of "
                         f"{', '.join(named)}")


def cell_request(tree: Path, cell: Path, seed: int, calibration: Path | None, log: Path | None, max_ticks: int,
                 assignments: list[str], goal: str | None, color: str | None, lift_height: float,
                 leaves: tuple[str, ...]) -> CellRunRequest:
    """The run's request from ``run``'s options (the blackboard as a simulated run's: ``lift_height``, ``color``,
    ``--set``)."""
    from bt_grasp.episode.cell_run import CellRunRequest
    from bt_grasp.episode.request import BlackboardValue, parse_assignments
    from bt_grasp.files.output_files import check_output_file

    blackboard: dict[str, BlackboardValue] = {"lift_height": lift_height}
    if color is not None:
        blackboard["color"] = color
    blackboard.update(parse_assignments(assignments))
    judged = None
    if goal is not None:
        from bt_grasp.scene.run_goal import goal_from_options

        judged = goal_from_options(goal, "red" if color is None else color, lift_height)
    if log is not None:
        check_output_file(log, "--log", example="run.mcap", inputs=(tree, cell, calibration))
    return CellRunRequest(tree=tree, cell=cell, seed=seed, goal=judged, calibration=calibration, log=log,
                          max_ticks=max_ticks, blackboard=blackboard, argv=tuple(sys.argv), leaves=leaves)


def ask(sentence: str) -> bool:
    """Ask on the terminal (standard error, so --json output stays clean); only a typed y or yes moves the arm."""
    sys.stderr.write(f"{sentence} [y/N] ")
    sys.stderr.flush()
    answer = sys.stdin.readline()
    return answer.strip().lower() in ("y", "yes")


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def run_cell(request: CellRunRequest, *, yes: bool, as_json: bool, summary_json: Path | None,
             show_failure: Callable[[FailureEvent], None] | None) -> int:
    """Run ``request`` and print its summary; the exit code (0 when the run succeeded, 1 otherwise).
    ``show_failure``: prints each leaf failure as it happens (None: quiet)."""
    from bt_grasp.episode.cell_run import CellEpisode
    from bt_grasp.files.output_files import write_output_file

    if not yes and not sys.stdin.isatty():
        raise InputError("--yes", "a run on a real cell asks before the arm's first motion and standard input is not "
                         "a terminal: give --yes to confirm it in advance")
    # Ctrl-C and SIGTERM reach the run (a shell may start a background job with SIGINT ignored): the run sends
    # stopJ, finishes its log and ends with exit code 130
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    episode = CellEpisode(request, None if yes else ask)  # bad input stops here: nothing opened
    if show_failure is not None:
        episode.on_failure.append(show_failure)
    outcome = episode.run()
    if summary_json is not None:
        write_output_file(summary_json, json.dumps(outcome.to_json(), indent=2) + "\n", "--summary-json")
    if as_json:
        print(json.dumps(outcome.to_json()))
    else:
        print_cell_summary(Console(), outcome)
    return 0 if outcome.result.success else 1


def print_cell_summary(console: Console, outcome: CellRunResult) -> None:
    summary = outcome.result
    verdict = "[bold green]SUCCESS[/]" if summary.success else "[bold red]FAILURE[/]"
    judged = summary.judged
    facts = "; ".join(detail for _c, _m, detail in judged.conditions)
    console.print(f"\n{verdict}  (tree: {escape(summary.tree_status)}; judged by {escape(judged.source)}: "
                  f"{escape(facts)})")
    console.print(f"  ran on the {outcome.ran_on} at {escape(outcome.address)}, on the wall clock")
    if not summary.success:
        leaf = summary.failed_path or summary.failed_leaf
        console.print(f"  reason: [red]{escape(str(summary.reason))}[/]" + (f"  leaf: {escape(str(leaf))}" if leaf
                                                                             else ""))
    if outcome.fault:
        console.print(f"  the cell ended the run: {escape(outcome.fault)} (the arm was stopped)")
    console.print(f"  ticks {summary.ticks}, {summary.wall_time_s:.2f} s, {outcome.overruns} late periods")
    if summary.log:
        console.print(f"  log: {escape(summary.log)}  (bt-grasp replay {escape(summary.log)})")
