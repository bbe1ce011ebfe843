"""`bt-grasp run TREE --scene SCENE`: run a task tree on the simulated cell and judge it by physics."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.console import Console
from rich.text import Text

from bt_grasp.cli.choices import GoalChoice
from bt_grasp.cli.plugin_option import leaves_option
from bt_grasp.cli.text_width import wrap
from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M, DEFAULT_MAX_TICKS
from bt_grasp.errors import InputError

if TYPE_CHECKING:  # the episode package (numpy, pydantic, the simulator) is imported when a run starts
    from bt_grasp.control.breakpoints import Breakpoint
    from bt_grasp.episode import TickCallback
    from bt_grasp.episode.request import EpisodeRequest
    from bt_grasp.episode.result import EpisodeResult
    from bt_grasp.scene.goals import Goal
    from bt_grasp.tree.loader import LoadedTree
    from bt_grasp.tree.runner import FailureEvent


#: the live view's port when ``--live`` has no value (bt_grasp.foxglove.live.DEFAULT_PORT, not imported here
#: so that a run without --live does not load the WebSocket server)
LIVE_DEFAULT_PORT = 8765
#: the run summary's causal chain shows at most this many failures (the last ones)
CHAIN_SHOWN = 8

#: options whose value may be left out (``--live`` alone means ``--live 8765``); click/typer have no such
#: option type, so :func:`fill_optional_values` writes the default in before parsing
OPTIONAL_VALUES = {"--live": str(LIVE_DEFAULT_PORT), "--realtime": "1.0"}


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def fill_optional_values(args: list[str]) -> list[str]:
    """``--live`` / ``--realtime`` followed by no number get their default value (``--live=8765``).

    A following token is taken as the value only when it is a number, so ``--live trees/pick.xml`` keeps the
    tree as the positional argument.
    """
    out: list[str] = []
    for i, token in enumerate(args):
        if token in OPTIONAL_VALUES and (i + 1 >= len(args) or not _is_number(args[i + 1])):
            out.append(f"{token}={OPTIONAL_VALUES[token]}")
        else:
            out.append(token)
    return out


def judged_phrase(summary: EpisodeResult) -> str:
    """The judge's view in a few words: the goal and what was measured."""
    verdict = summary.judged
    facts = "; ".join(detail for _criterion, _met, detail in verdict.conditions)
    return f"goal {summary.goal.kind} judged by physics: {facts}"


def print_summary(console: Console, summary: EpisodeResult) -> None:
    """The run's summary, within the console's width (80 in a pipe): sentences wrap between words with a hanging
    indent, no value is cut, and the `bt-grasp replay LOG` command stands alone on one line, whole, so it can be
    copied. Text from the user's files (leaf names, reasons, paths) is printed as text, never as Rich markup."""
    width = console.width

    def say(text: str, indent: str = "  ", hang: str = "  ", styles: tuple[tuple[str, str], ...] = ()) -> None:
        line = Text(wrap(text, indent=indent, hang=hang, width=width))
        for part, style in styles:  # colour each part where it first stands
            at = line.plain.find(part)
            if part and at >= 0:
                line.stylize(style, at, at + len(part))
        console.print(line, soft_wrap=True, highlight=False)

    verdict = "SUCCESS" if summary.success else "FAILURE"
    console.print()
    say(f"{verdict}  (tree: {summary.tree_status}, {judged_phrase(summary)})", indent="",
        styles=((verdict, "bold green" if summary.success else "bold red"),))
    unmet = summary.unmet()
    if not summary.success and summary.tree_status == "SUCCESS" and unmet is not None:
        # the tree succeeded and the goal did not: the headline is the goal's first unmet condition (issue 46)
        say(f"goal not met: {unmet[0]}: {unmet[1]}", styles=((f"goal not met: {unmet[0]}", "red"),))
    elif not summary.success:
        leaf = summary.failed_path or summary.failed_leaf  # the path: the leaf's name in every output
        say(f"reason: {summary.reason}  leaf: {leaf}", styles=((f"reason: {summary.reason}", "red"),))
        if unmet is not None:
            say(f"goal not met: {unmet[0]}: {unmet[1]}")
    say(f"ticks {summary.ticks}, simulated {summary.sim_time_s:.2f} s, wall {summary.wall_time_s:.2f} s, "
        f"seed {summary.seed}")
    if summary.retries:
        say("retries: " + ", ".join(f"{k} x{v}" for k, v in summary.retries.items()))
    if summary.faults_fired:
        say(f"faults fired: {summary.faults_fired}")
        for firing in summary.faults:  # what each hit; a push on an object the tree never touched says so
            say(firing.sentence(), indent="    ", styles=((firing.sentence(), "yellow"),) if firing.missed else ())
    if summary.log:  # each on a line of its own, never broken: a path and a command to copy
        console.print(Text(f"  log: {summary.log}"), soft_wrap=True, highlight=False)
        console.print(Text(f"  replay: bt-grasp replay {summary.log}"), soft_wrap=True, highlight=False)
    chain = summary.failure_chain
    if chain:  # last: the causal chain of the failures (conditions false by design left out)
        say("what failed, and what followed (oldest first):")
        if len(chain) > CHAIN_SHOWN:
            say(f"... {len(chain) - CHAIN_SHOWN} earlier failures (bt-grasp replay LOG --failures)", indent="    ")
        for step in chain[-CHAIN_SHOWN:]:
            reason = str(step.reason or "-")
            say(f"tick {step.tick} ({step.sim_time_s:.2f} s) {step.leaf_path} {reason} -> {step.followed}",
                indent="    ", styles=((f" {reason} ->", "red"),))


def failure_line(console: Console) -> Callable[[FailureEvent], None]:
    """Prints one line per leaf FAILURE as it happens (not the conditions false by design): leaf path,
    reason, tick, simulated time."""

    def show(event: FailureEvent) -> None:
        text = (f"FAILED {event.path}: {event.reason or '-'} at tick {event.tick}, t={event.stamp_ns * 1e-9:.2f} s"
                + (f" ({event.message})" if event.message else ""))
        # on a terminal, over the progress line (which ends with a carriage return); elsewhere wrapped to the width
        console.print(text.ljust(console.width - 1) if console.is_terminal else wrap(text, width=console.width),
                      style="red", highlight=False, markup=False, soft_wrap=True)

    return show


def live_progress(console: Console) -> TickCallback:
    """A tick hook that shows the active leaf, its feedback, the tick and the simulated time: one line redrawn in
    place, on a terminal only (in a pipe or a file, progress is noise between the lines that matter)."""

    def hook(tick: int, tree: LoadedTree) -> None:
        if not console.is_terminal:
            return
        running = [n for n in tree.nodes() if n.bt_state.value == "RUNNING" and not n.children]
        leaf = running[-1] if running else None
        text = f"tick {tick:5d}  t={tree.clock.now_ns() * 1e-9:6.2f} s  " + (
            f"{leaf.name}: {leaf.feedback_message}" if leaf is not None else ""
        )
        console.print(text[: console.width - 1], end="\r", highlight=False, soft_wrap=True, markup=False)

    return hook


def run(
    tree: Path = typer.Argument(..., help="Tree file: BehaviorTree.CPP v4 XML or bt_grasp YAML."),
    scene: Path | None = typer.Option(None, "--scene", help="Scene YAML file (a run on the simulator)."),
    cell: Path | None = typer.Option(None, "--cell", help="Cell YAML file: run on a real cell (a UR through ur_rtde "
                                     "and a RealSense) or a twin of one, on the wall clock (docs/real-cell.md)."),
    yes: bool = typer.Option(False, "--yes", help="With --cell: do not ask before the arm's first motion."),
    seed: int = typer.Option(0, "--seed", help="Seed of object poses, camera noise, planners and faults."),
    calibration: Path | None = typer.Option(None, "--calibration", help="Calibration YAML from `bt-grasp calibrate`."),
    log: Path | None = typer.Option(None, "--log", help="Write the run to this MCAP file."),
    max_ticks: int = typer.Option(DEFAULT_MAX_TICKS, "--max-ticks", min=1, help="Stop after this many ticks."),
    summary_json: Path | None = typer.Option(None, "--summary-json", help="Also write the summary as JSON here."),
    faults: Path | None = typer.Option(None, "--faults", help="Fault plan YAML."),
    inject: list[str] = typer.Option([], "--inject", help="A fault, e.g. 'frame_drop@Perceive#1' (repeatable)."),
    set_: list[str] = typer.Option([], "--set", help="Blackboard entry KEY=VALUE before the first tick."),
    goal: GoalChoice | None = typer.Option(
        None, "--goal", help="What the judge checks: pick (held and lifted) or clear; default: the scene's goal, "
        "else pick (the other goals, e.g. stack, are declared in the scene file)."
    ),
    color: str | None = typer.Option(
        None, "--color", help="The pick goal's colour, also {color} for the tree ('' = any). Default: red, or any "
        "object on a scene with mesh or URDF objects."),
    lift_height: float = typer.Option(
        DEFAULT_LIFT_HEIGHT_M, "--lift-height", help="The pick goal's lift height in metres, also {lift_height}."
    ),
    quiet: bool = typer.Option(False, "--quiet", help="No live progress."),
    as_json: bool = typer.Option(
        False, "--json", help="Print the summary as exactly one JSON object on stdout (the text summary is left out; "
        "progress stays on stderr)."
    ),
    live: int | None = typer.Option(
        None, "--live", metavar="[PORT]",
        help=f"Serve the run live to Foxglove (WebSocket on 127.0.0.1, port {LIVE_DEFAULT_PORT} unless given).",
    ),
    live_host: str = typer.Option("127.0.0.1", "--live-host", help="Address the live server binds to."),
    realtime: float | None = typer.Option(
        None, "--realtime", metavar="[FACTOR]",
        help="Pace wall time to simulated time (FACTOR simulated seconds per wall second; default 1).",
    ),
    image_hz: float = typer.Option(
        0.0, "--image-hz", min=0.0, help="Extra logged camera frames per simulated second (0: only at a leaf's "
        "failure and at the end; each costs a render)."
    ),
    resident: bool = typer.Option(
        False, "--resident", help="Run in this user's resident warm process (started if needed; it exits after "
        "10 idle minutes): a second run skips the start-up. No live progress, no --live."
    ),
    leaves: list[str] = leaves_option(),
    interactive: bool = typer.Option(
        False, "--interactive", help="Run in a terminal UI: the tree's live statuses, the blackboard, the last "
        "failure; keys pause, step, break on failure, set an entry, choose the object, fire a fault, restart, quit "
        "(docs/interactive.md). Starts paused."
    ),
    break_: list[str] = typer.Option(
        [], "--break", metavar="SPEC", help="With --interactive, pause at: node:NAME (before it starts), fail (a "
        "leaf FAILURE not false by design, as replay --failures lists them), fail:REASON, fail:all (every leaf "
        "FAILURE), bb:KEY (it changed), tick:N, time:S (repeatable)."
    ),
    control: bool = typer.Option(
        False, "--control", help="With --live: take commands from Foxglove (the Parameters and Publish panels of "
        "the control layout: pause, step, breakpoints, blackboard, object, faults, stop; docs/interactive.md). "
        "Starts paused; only on a loopback --live-host."
    ),
    allow_remote_control: bool = typer.Option(
        False, "--allow-remote-control", help="Accept --control on a --live-host other machines reach (no "
        "authentication: a warning is printed)."
    ),
    control_files: Path | None = typer.Option(
        None, "--control-files", metavar="DIR", help="With --control: a viewer may set a blackboard entry that names "
        "a file (bb.calibration_file) only to a file under DIR (default: none at all; any user of this machine can "
        "reach a loopback port)."
    ),
) -> None:
    """Run a task tree on the simulated cell (or a real one: --cell). Exit code 0 on task success (judged by physics),
    1 on failure."""
    if cell is not None or scene is None:
        from bt_grasp.cli.cell_run_options import cell_request, refuse_simulator_options, run_cell

        if scene is not None or cell is None:
            raise InputError("--scene", "give one of --scene SCENE (the simulator) or --cell CELL (a real cell), "
                             f"{'not both' if scene is not None else 'got neither'}")
        refuse_simulator_options({"--faults": faults is not None, "--inject": bool(inject), "--live": live is not None,
                                  "--realtime": realtime is not None, "--image-hz": image_hz > 0,
                                  "--resident": resident, "--interactive": interactive, "--break": bool(break_),
                                  "--control": control})
        on_cell = cell_request(tree, cell, seed, calibration, log, max_ticks, set_, goal.value if goal else None,
                               color, lift_height, tuple(leaves))
        show = None if quiet else failure_line(Console(stderr=True))
        raise typer.Exit(run_cell(on_cell, yes=yes, as_json=as_json, summary_json=summary_json, show_failure=show))
    # only what every run needs here: a --resident run's client hands the request over and imports neither the
    # episode (the simulator's modules) nor the control package (issue 27)
    from bt_grasp.episode.request import EpisodeRequest, parse_assignments, run_blackboard
    from bt_grasp.files.output_files import check_output_file, write_output_file
    from bt_grasp.recording.reproducible import log_epoch_ns

    # not given, no color: the scene's default (bt_grasp.scene.run_goal.default_color); a campaign's episode gets
    # its blackboard by the same rule
    blackboard = run_blackboard(parse_assignments(set_), color=color, lift_height=lift_height)
    request = EpisodeRequest(
        tree=tree,
        scene=scene,
        seed=seed,
        goal=_goal(goal.value, "red" if color is None else color, lift_height) if goal is not None else None,
        calibration=calibration,
        log=log,
        max_ticks=max_ticks,
        faults=faults,
        inject=tuple(inject),
        blackboard=blackboard,
        argv=tuple(sys.argv),
        image_hz=image_hz,
        live_port=live,
        live_host=live_host,
        realtime=realtime,
        leaves=tuple(leaves),
        log_epoch_ns=log_epoch_ns(os.environ),
    )
    if realtime is not None and realtime <= 0:
        raise InputError("--realtime", f"the factor must be positive, got {realtime}")
    breakpoints: tuple[Breakpoint, ...] = ()
    if break_:
        from bt_grasp.control.breakpoints import parse_breakpoints

        breakpoints = parse_breakpoints(break_)
    if breakpoints and not (interactive or control):
        raise InputError("--break", "breakpoints need --interactive or --control (a front end to continue from them)")
    if interactive and control:
        raise InputError("--control", "a run takes commands from the terminal (--interactive) or from Foxglove "
                         "(--control), not both; drop one of the two")
    if control and live is None:
        raise InputError("--control", "takes commands from a live viewer, so it needs --live")
    if control_files is not None and not control:
        raise InputError("--control-files", "names the folder a viewer's file names must lie in, so it needs --control")
    if control_files is not None and not control_files.is_dir():
        raise InputError("--control-files", f"'{control_files}' is not a folder")
    if interactive and as_json:
        raise InputError("--json", "an interactive run draws on the terminal; drop --json or --interactive")
    if interactive and resident:
        raise InputError("--interactive", "an interactive run cannot be --resident; drop one of the two")
    if summary_json is not None:  # a path it cannot be written to is said before the run, not after it
        check_output_file(summary_json, "--summary-json", example="summary.json",
                          inputs=(tree, scene, calibration, faults))
    console = Console(stderr=True)
    if live is not None:
        from bt_grasp.cli.live_log import show_live_server_log

        show_live_server_log()  # a viewer's bytes quoted in the SDK's lines are shown, never obeyed
    from bt_grasp.files.hosts import is_loopback

    if live is not None and not is_loopback(live_host):
        console.print(exposure_warning(live_host), highlight=False, markup=False)
    if resident:
        from bt_grasp.resident.client import run_resident

        if live is not None:
            raise InputError("--resident", "a resident run cannot serve --live; drop one of the two")
        summary, pid = run_resident(request)
        console.print(f"(ran in the resident process {pid})", highlight=False)
    elif interactive:
        summary = _run_interactive(request, breakpoints)
    else:
        from bt_grasp.foxglove.tree_layout import live_layout_folder

        layouts = live_layout_folder(live is not None, request.log)  # removed when the run ends
        try:
            summary = _run_served(request, breakpoints, console, quiet=quiet, control=control,
                                  allow_remote=allow_remote_control, control_files=control_files,
                                  layout_folder=Path(layouts.name) if layouts is not None else None)
        finally:
            if layouts is not None:
                layouts.cleanup()
    if summary_json is not None:  # written first: nothing printed may stand between a run and its record
        write_output_file(summary_json, json.dumps(summary.to_json(), indent=2) + "\n", "--summary-json")
    if as_json:
        typer.echo(json.dumps(summary.to_json()))
    else:
        print_summary(Console(), summary)
    raise typer.Exit(0 if summary.success else 1)


def _run_served(request: EpisodeRequest, breakpoints: tuple[Breakpoint, ...], console: Console, *, quiet: bool,
                control: bool, allow_remote: bool, layout_folder: Path | None,
                control_files: Path | None = None) -> EpisodeResult:
    """A run in this process, served live (with ``--control``, driven from the viewer) when asked."""
    on_tick = () if quiet else (live_progress(console),)
    if control:
        from bt_grasp.episode.foxglove_run import run_foxglove_control

        def say(line: str) -> None:
            console.print(line, highlight=False, markup=False)

        return run_foxglove_control(request, breakpoints, allow_remote=allow_remote, say=say,
                                    on_tick=on_tick, layout_folder=layout_folder, control_files=control_files)
    from bt_grasp.episode.episode import Episode

    episode = Episode(request)
    if not quiet:
        episode.on_failure.append(failure_line(console))
    if request.live_port is not None:  # the layout of this tree (its leaves' rows), beside the log or in the folder
        from bt_grasp.foxglove.tree_layout import write_live_layout

        layout = write_live_layout(request.tree, request.leaves, request.log, folder=layout_folder)
        episode.on_live.append(lambda url: console.print(
            f"live: in Foxglove, Open connection > Foxglove WebSocket > {url} (layout: {layout})",
            highlight=False, markup=False, soft_wrap=True))
    return episode.run(on_tick=on_tick)


def _run_interactive(request: EpisodeRequest, breakpoints: tuple[Breakpoint, ...]) -> EpisodeResult:
    """The terminal UI over one episode (and those its restarts start: logs run-2.mcap, run-3.mcap, ...)."""
    from dataclasses import replace

    from bt_grasp.control import check_breakpoints
    from bt_grasp.episode.episode import Episode

    if not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise InputError("--interactive", "needs a terminal, and standard input or output is not one")
    first = Episode(request)  # bad input stops here, before the UI takes the terminal
    check_breakpoints(first.tree, breakpoints)
    from bt_grasp.cli.interactive_ui import InteractiveApp, Session
    from bt_grasp.control import Controller

    results: list[EpisodeResult] = []

    def run_one(controller: Controller, seed: int, number: int) -> str:
        log = request.log
        if number and log is not None:
            log = log.with_name(f"{log.stem}-{number + 1}{log.suffix}")
        episode = first if number == 0 else Episode(replace(request, seed=seed, log=log))
        result = episode.run(controller=controller)
        results.append(result)
        return (f"{'SUCCESS' if result.success else 'FAILURE'} after {result.ticks} ticks, seed {seed}"
                + (f", reason {result.reason}" if result.reason else "") + (f", log {log}" if log else ""))

    app = InteractiveApp(Session(run_one, request.seed, breakpoints))
    try:
        app.run()
    finally:
        app.stop_and_wait()
    if app.error is not None:
        raise app.error
    if not results:
        raise InputError("--interactive", "the run did not start")
    return results[-1]


def exposure_warning(host: str) -> str:
    from bt_grasp.files.hosts import exposure_warning as warning

    return warning("--live-host", host, "this run (Foxglove WebSocket)", 8765)


def _goal(kind: str, color: str, lift_height: float) -> Goal:
    """``--goal``'s goal (the scene module it needs is imported only when the option is given)."""
    from bt_grasp.scene.run_goal import goal_from_options

    return goal_from_options(kind, color, lift_height)


def register(app: typer.Typer) -> None:
    app.command("run")(run)
