"""`bt-grasp bench eval`: episodes per minute, today's `bench pick` loop vs campaigns on 1 and N workers."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bt_grasp.cli.bench_cmd import EPISODE_BENCHMARKS, bench_app


@bench_app.command("eval", rich_help_panel=EPISODE_BENCHMARKS)
def bench_eval(
    trees: list[Path] = typer.Option(
        [Path("trees/pick.xml"), Path("trees/pick_with_recovery.xml")], "--tree", help="Tree(s) to run."
    ),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene"),
    seeds: int = typer.Option(6, "--seeds", min=1, help="Seeded episodes per tree."),
    first_seed: int = typer.Option(0, "--first-seed"),
    workers: list[int] = typer.Option([1, 2], "--workers", help="Worker counts to measure (repeatable)."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Episodes per minute, side by side: `bench pick`'s loop, then a campaign on each worker count. (A developer
    benchmark of campaigns themselves: to evaluate a tree, `bt-grasp eval run --tree T --scene S --seeds N`.)"""
    from bt_grasp.bench.eval_speed import run_eval_bench

    report = run_eval_bench(trees, scene, seeds, first_seed, workers)
    if as_json:
        typer.echo(json.dumps(report))
        return
    typer.echo(f"{report['machine']}; load average before {report['load_before']}, after {report['load_after']}")
    for name, r in report["runs"].items():
        extra = (f", per-episode setup (warm) median {r['setup_s_median_warm']} s" if "setup_s_median_warm" in r
                 else "")
        typer.echo(f"{name:52s} {r['episodes']} episodes ({r['successes']} ok) in {r['wall_s']} s: "
                   f"{r['episodes_per_min']} episodes/min{extra}")
    typer.echo(f"same fingerprints for every worker count: {report['same_fingerprints_across_worker_counts']}")


def register(app: typer.Typer) -> None:
    """The command above attaches itself to bench_cmd's group when this module is imported."""
