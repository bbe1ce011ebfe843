"""`bt-grasp run TREE --scene SCENE`: run a task tree on the simulated cell and judge it by physics."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import typer
from rich.console import Console

from bt_grasp.cli.session import DEFAULT_MAX_TICKS, RunRequest, RunSummary, parse_assignments


def print_summary(console: Console, summary: RunSummary) -> None:
    verdict = "[bold green]SUCCESS[/]" if summary.success else "[bold red]FAILURE[/]"
    task = summary.judge.get("task", "pick")
    if task == "pick":
        held = summary.judge["in_gripper"]
        judged = f"judged by physics: lift {summary.object_lift_m * 100:.1f} cm, in gripper: {held}"
    elif task == "clear":
        left = summary.judge["objects_in_workspace"] or "none"
        judged = f"judged by physics: objects left in the work area: {left}"
    else:
        judged = "no physical goal: the tree's own result"
    console.print(f"\n{verdict}  (tree: {summary.tree_status}, {judged})")
    if not summary.success:
        console.print(f"  reason: [red]{summary.reason}[/]  leaf: {summary.failed_leaf}")
    console.print(
        f"  ticks {summary.ticks}, simulated {summary.sim_time_s:.2f} s, "
        f"wall {summary.wall_time_s:.2f} s, seed {summary.seed}"
    )
    if summary.retries:
        console.print("  retries: " + ", ".join(f"{k} x{v}" for k, v in summary.retries.items()))
    if summary.faults_fired:
        console.print(f"  faults fired: {summary.faults_fired}")
    if summary.log:
        console.print(f"  log: {summary.log}  (bt-grasp replay {summary.log})")


def live_progress(console: Console) -> Any:
    """A tick hook that shows the active leaf, its feedback, the tick and the simulated time."""
    state = {"last": ""}

    def hook(tick: int, tree: Any) -> None:
        if not console.is_terminal and tick % 100:
            return
        running = [n for n in tree.nodes() if n.bt_state.value == "RUNNING" and not n.children]
        leaf = running[-1] if running else None
        text = f"tick {tick:5d}  t={tree.clock.now_ns() * 1e-9:6.2f} s  " + (
            f"{leaf.name}: {leaf.feedback_message}" if leaf is not None else ""
        )
        if console.is_terminal:
            console.print(text[: console.width - 1], end="\r", highlight=False, soft_wrap=True)
        elif text != state["last"]:
            console.print(text, highlight=False)
        state["last"] = text

    return hook


def run(
    tree: Path = typer.Argument(..., help="Tree file: BehaviorTree.CPP v4 XML or bt_grasp YAML."),
    scene: Path = typer.Option(..., "--scene", help="Scene YAML file."),
    seed: int = typer.Option(0, "--seed", help="Seed of object poses, camera noise, planners and faults."),
    calibration: Path | None = typer.Option(None, "--calibration", help="Calibration YAML from `bt-grasp calibrate`."),
    log: Path | None = typer.Option(None, "--log", help="Write the run to this MCAP file."),
    max_ticks: int = typer.Option(DEFAULT_MAX_TICKS, "--max-ticks", min=1, help="Stop after this many ticks."),
    summary_json: Path | None = typer.Option(None, "--summary-json", help="Also write the summary as JSON here."),
    faults: Path | None = typer.Option(None, "--faults", help="Fault plan YAML."),
    inject: list[str] = typer.Option([], "--inject", help="A fault, e.g. 'frame_drop@Perceive#1' (repeatable)."),
    set_: list[str] = typer.Option([], "--set", help="Blackboard entry KEY=VALUE before the first tick."),
    color: str = typer.Option("red", "--color", help="Target colour for trees that read {color} ('' = any)."),
    lift_height: float = typer.Option(0.15, "--lift-height", help="Lift height in metres ({lift_height})."),
    quiet: bool = typer.Option(False, "--quiet", help="No live progress."),
) -> None:
    """Run a task tree on the simulated cell. Exit code 0 on task success (judged by physics), 1 on failure."""
    from bt_grasp.cli.session import Prepared, execute

    blackboard: dict[str, Any] = {"color": color, "lift_height": lift_height}
    blackboard.update(parse_assignments(set_))
    request = RunRequest(
        tree=tree,
        scene=scene,
        seed=seed,
        calibration=calibration,
        log=log,
        max_ticks=max_ticks,
        faults=faults,
        inject=tuple(inject),
        blackboard=blackboard,
        argv=tuple(sys.argv),
    )
    console = Console(stderr=True)
    prepared = Prepared(request)
    summary, _stream = execute(prepared, None if quiet else live_progress(console))
    out = Console()
    print_summary(out, summary)
    if summary_json is not None:
        summary_json.parent.mkdir(parents=True, exist_ok=True)
        summary_json.write_text(json.dumps(summary.to_json(), indent=2) + "\n")
    raise typer.Exit(0 if summary.success else 1)


def register(app: typer.Typer) -> None:
    app.command("run")(run)
