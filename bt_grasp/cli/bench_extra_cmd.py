"""More `bt-grasp bench` commands: pick success over seeds, the simulated cell, tree ticks, logging."""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

from bt_grasp.cli.bench_cmd import EPISODE_BENCHMARKS, MICRO_BENCHMARKS, bench_app
from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.process.environment import machine_description


@bench_app.command("pick", rich_help_panel=EPISODE_BENCHMARKS)
def pick(
    trees: list[Path] | None = typer.Option(
        None, "--tree", help="Tree(s) to run. Default: trees/pick.xml and trees/pick_with_recovery.xml; with "
                             "--detector learned, trees/pick_class.xml and trees/pick_with_recovery.xml."
    ),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene"),
    seeds: int = typer.Option(20, "--seeds", min=1, help="Number of seeded episodes per tree."),
    first_seed: int = typer.Option(0, "--first-seed"),
    calibration: Path | None = typer.Option(None, "--calibration", help="Default: calibrate once first."),
    log_dir: Path | None = typer.Option(None, "--log-dir", help="Keep every run's MCAP log here."),
    as_json: bool = typer.Option(False, "--json"),
    warm: bool = typer.Option(
        False, "--warm", help="Keep the renderer warm between episodes (each episode's world is still built afresh)."
    ),
    color: str | None = typer.Option(
        None, "--color", help="Colour the tree picks ('' = any object, by geometry). Default: red, or any object "
                              "on a scene with mesh or URDF objects."),
    detector: DetectorKind = typer.Option(
        DetectorKind.GEOMETRIC, "--detector",
        help="learned: pick by class; each seed names a target on its table, its class as {class} (e.g. "
             "trees/pick_class.xml) and its colour as {color} (e.g. trees/pick_with_recovery.xml: the geometric "
             "detector on the same targets), judged on that object."),
) -> None:
    """Pick success over seeded episodes, judged by physics (object held 15 cm up at the end), per tree and per
    object picked, with why each failure failed. (A developer benchmark, in one process: to evaluate a tree,
    `bt-grasp eval run --tree T --scene S --seeds N`.)"""
    from bt_grasp.bench.pick import default_pick_trees, run_pick_bench

    trees = trees or default_pick_trees(detector.value)
    err = Console(stderr=True)  # progress on stderr: stdout stays one JSON object with --json
    report = run_pick_bench(trees, scene, seeds, first_seed, calibration, log_dir, warm, color,
                            progress=lambda line: err.print(line, highlight=False, markup=False, soft_wrap=True),
                            detector=detector.value)
    if as_json:
        typer.echo(json.dumps(report))
        return
    table = Table(title=f"pick over {seeds} seeds ({report['machine']})")
    for col in ("tree", "success", "median sim s", "median wall s", "plans/pick", "plan s/pick", "retries",
                "failures"):
        table.add_column(col)
    for tree, r in report["trees"].items():
        table.add_row(
            tree,
            f"{r['successes']}/{r['runs']}",
            f"{r['sim_time_s_median']:.2f}",
            f"{r['wall_time_s_median']:.2f}",
            f"{r['plan_calls_per_pick_mean']:.2f}",
            f"{r['plan_wall_s_per_pick_median']:.3f}",
            str(r["retries_total"]),
            json.dumps(r["failures"]),
        )
    console = Console()
    console.print(table)
    for seed, problem in report.get("unplaced_seeds", {}).items():
        console.print(f"seed {seed} not run: {problem} (the scene's objects do not fit at this seed)", highlight=False,
                      markup=False)
    for tree, r in report["trees"].items():
        for name, o in r["per_object"].items():
            reasons = ", ".join(f"{k} x{v}" for k, v in o["failure_reasons"].items()) or "-"
            console.print(f"{tree}: {name} {o['successes']}/{o['runs']} (failures: {reasons})", highlight=False,
                          markup=False)


@bench_app.command("sim", rich_help_panel=MICRO_BENCHMARKS)
def sim(
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene"),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Scene build time, RGB-D capture time on this renderer, physics speed with no rendering."""
    from bt_grasp.bench.sim import run_sim_bench

    report = run_sim_bench(scene)
    typer.echo(json.dumps(report) if as_json else "\n".join(f"{k:24s} {v}" for k, v in report.items()))


@bench_app.command("tree", rich_help_panel=MICRO_BENCHMARKS)
def tree(
    nodes: int = typer.Option(100, "--nodes"),
    ticks: int = typer.Option(2000, "--ticks"),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Tick overhead of the tree runtime itself (no physics, no rendering), per node per tick."""
    from bt_grasp.bench.tree import tick_overhead

    report = {"machine": machine_description(), **tick_overhead(nodes, ticks)}
    typer.echo(json.dumps(report) if as_json else "\n".join(f"{k:24s} {v}" for k, v in report.items()))


@bench_app.command("logging", rich_help_panel=MICRO_BENCHMARKS)
def logging_bench(
    ticks: int = typer.Option(6000, "--ticks"),
    nodes: int = typer.Option(40, "--nodes"),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """MCAP logging cost per tick and file size per simulated minute; summary time of a 10,000-tick log."""
    from bt_grasp.bench.recording import bench_logging, bench_reading

    t0 = time.perf_counter()
    report: dict[str, object] = {
        "machine": machine_description(), "write": bench_logging(ticks, nodes), "read": bench_reading(10000)
    }
    report["elapsed_s"] = round(time.perf_counter() - t0, 2)
    typer.echo(json.dumps(report) if as_json else json.dumps(report, indent=2))


def register(app: typer.Typer) -> None:
    """The commands above attach themselves to bench_cmd's group when this module is imported."""


@bench_app.command("budget", rich_help_panel=MICRO_BENCHMARKS)
def budget(
    tree: Path = typer.Option(Path("trees/pick.xml"), "--tree"),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene"),
    seed: int = typer.Option(0, "--seed"),
    calibration: Path | None = typer.Option(None, "--calibration", help="Default: the file the scene names."),
    log: bool = typer.Option(True, "--log/--no-log", help="Record the measured pick to a temporary MCAP log."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Where one warm pick's time goes, by stage, with the floor (physics alone + one capture) beside it."""
    from bt_grasp.bench.budget import run_budget_bench

    report = run_budget_bench(tree, scene, seed, calibration, log)
    if as_json:
        typer.echo(json.dumps(report))
        return
    total = report["episode_wall_s"]
    table = Table(title=Text(f"one warm pick: {tree} on {scene}, seed {seed}, log {'on' if log else 'off'} "
                             f"({report['ticks']} ticks, {report['sim_time_s']} s simulated; {report['machine']})"))
    for col in ("group", "stage", "wall s", "share", "calls"):
        table.add_column(col)
    for row in report["stages"]:
        table.add_row(row["group"], row["stage"], f"{row['s']:.3f}", f"{100 * row['share']:.1f}%", str(row["calls"]))
    table.add_row("", "total (Episode.run)", f"{total:.3f}", "100%", "")
    console = Console()
    console.print(table)
    floor = report["floor"]
    overhead = report["tick_loop_overhead_us_per_tick"]
    console.print(
        f"floor: physics of the same {report['physics_steps']} steps alone {floor['physics_s']:.3f} s "
        f"({floor['physics_steps_per_s']:.0f} steps/s, measured now) + one capture {floor['capture_s']:.3f} s = "
        f"{floor['floor_s']:.3f} s; this pick {total:.3f} s = {report['wall_over_floor']:.2f}x the floor "
        f"(tick loop alone {report['tick_loop_wall_s']:.3f} s)\n"
        f"tick loop's own overhead per tick: py_trees {overhead['tree (py_trees)']:.0f} us, status bookkeeping "
        f"{overhead['status bookkeeping']:.0f} us, blackboard differ {overhead['blackboard differ']:.0f} us, "
        f"recording {overhead['recording']:.0f} us; total {overhead['total']:.0f} us",
        highlight=False, soft_wrap=True,
    )


@bench_app.command("attempts", rich_help_panel=MICRO_BENCHMARKS)
def attempts(
    logs: list[Path] = typer.Argument(..., help="MCAP logs, or folders of them (e.g. a campaign's or bench pick "
                                                 "--log-dir's)."),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
) -> None:
    """Attempts counted from recorded runs' logs (/bt/attempts; rebuilt from the leaves' statuses in a log written
    before it): repeats of a failed attempt (same object and family, within 5 mm and 10 deg; 15 mm and 20 deg of
    a stall) and the attempts per failed episode."""
    from bt_grasp.bench.attempts import summarise

    summary = summarise(logs)
    if as_json:
        typer.echo(json.dumps(summary))
        return
    console = Console()
    console.print(f"{summary['episodes']} episode(s), {summary['failed']} failed; "
                  f"{summary['repeats']} repeated attempt(s) in {summary['episodes_with_repeats']} episode(s)",
                  highlight=False)
    spread = ", ".join(f"{n} attempt(s): {count}" for n, count in summary["attempts_per_failed_episode"].items())
    console.print(f"attempts per failed episode: {spread or '-'} (median "
                  f"{summary['attempts_per_failed_episode_median']}); mean attempts per episode "
                  f"{summary['attempts_per_episode_mean']}", highlight=False)
    for entry in summary["logs"]:
        if entry["repeats"]:
            pairs = ", ".join(f"#{b} repeats #{a}" for a, b in entry["repeats"])
            console.print(f"  {entry['log']}: {pairs}", highlight=False, markup=False)
