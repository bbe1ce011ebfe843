"""`bt-grasp bench twin` and `bt-grasp bench cell-faults`: a real cell's code path measured against the twin
(``bt_grasp.bench.twin``, ``bt_grasp.bench.cell_faults``; docs/real-cell.md)."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from bt_grasp.cli.bench_cmd import EPISODE_BENCHMARKS, MICRO_BENCHMARKS, bench_app


@bench_app.command("twin", rich_help_panel=EPISODE_BENCHMARKS)
def twin(
    seeds: int = typer.Option(20, "--seeds", min=1, help="Number of seeds: a twin of the scene each."),
    first_seed: int = typer.Option(0, "--first-seed"),
    tree: Path = typer.Option(Path("trees/pick_with_recovery.xml"), "--tree"),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene", help="The scene the twins serve."),
    log_dir: Path | None = typer.Option(None, "--log-dir", help="Keep every run's MCAP log here."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Seeded picks through ur_rtde, the Robotiq socket and pyrealsense2 against a twin started and stopped for
    each seed (real time), judged by the twin's physics. (A developer benchmark of the real-cell path.)"""
    from bt_grasp.bench.twin import run_twin_bench
    from bt_grasp.scene.format import load_scene

    load_scene(scene)  # a bad scene is one sentence before any twin starts
    err = Console(stderr=True)
    report = run_twin_bench(tree, scene, seeds, first_seed, log_dir,
                            progress=lambda line: err.print(line, highlight=False, markup=False, soft_wrap=True))
    if as_json:
        typer.echo(json.dumps(report))
        return
    console = Console()
    console.print(f"{report['tree']} on twins of {report['scene']}: {report['successes']}/{report['runs']} picks "
                  f"judged by the twin's physics; median run {report['wall_s_median']:.1f} s, twin up in "
                  f"{report['twin_start_s_median']:.1f} s, {report['late_periods_median']} late periods "
                  f"({report['machine']})", highlight=False)
    if report["failures"]:
        console.print("failures: " + ", ".join(f"{k} x{v}" for k, v in report["failures"].items()), highlight=False)


@bench_app.command("cell-faults", rich_help_panel=MICRO_BENCHMARKS)
def cell_faults(
    trials: int = typer.Option(10, "--trials", min=1, help="Trials per fault."),
    fault: list[str] = typer.Option([], "--fault", help="Only these faults (repeatable): protective-stop, "
                                    "twin-killed, gripper-silent, sigstop, ctrl-c."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Each fault injected mid-motion into a run against the twin: its reason, how soon the arm stood still and the
    run saw it, and whether replay reads the log. (A developer benchmark of the real-cell path.)"""
    from bt_grasp.bench.cell_faults import FAULTS, run_fault_bench
    from bt_grasp.errors import InputError

    unknown = [f for f in fault if f not in FAULTS]
    if unknown:
        raise InputError("--fault", f"unknown fault '{unknown[0]}'; known: {', '.join(FAULTS)}")
    err = Console(stderr=True)
    report = run_fault_bench(trials, tuple(fault) or tuple(FAULTS),
                             progress=lambda line: err.print(line, highlight=False, markup=False, soft_wrap=True))
    if as_json:
        typer.echo(json.dumps(report))
        return
    table = Table(title=f"faults mid-motion against the twin, {trials} trials each ({report['machine']})")
    for column in ("fault", "reason", "as expected", "arm still: median / worst ms", "run saw it: median / worst ms",
                   "replay reads"):
        table.add_column(column)
    for name, r in report["faults"].items():
        table.add_row(name, ", ".join(sorted(set(r["reasons"]))), f"{r['expected']}/{r['trials']}",
                      _ms(r["stop_ms"]), _ms(r["seen_ms"]), f"{r['replayed']}/{r['trials']}")
    Console().print(table)


def _ms(values: list[float]) -> str:
    if not values:
        return "-"
    ordered = sorted(values)
    return f"{ordered[len(ordered) // 2]:.0f} / {ordered[-1]:.0f}"


def register(app: typer.Typer) -> None:
    """The commands above attach themselves to bench_cmd's group when this module is imported."""
