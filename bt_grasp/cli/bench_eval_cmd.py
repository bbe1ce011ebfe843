"""`bt-grasp bench eval`: episodes per minute, today's `bench pick` loop vs campaigns on 1 and N workers."""

from __future__ import annotations

import json
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import typer

from bt_grasp.cli.bench_cmd import bench_app


def _campaign_file(folder: Path, trees: list[Path], scene: Path, seeds: int, first_seed: int) -> Path:
    path = folder / "bench.yaml"
    lines = ["name: bench", "trees:", *[f"  - {t.resolve()}" for t in trees], "scenes:", f"  - {scene.resolve()}",
             f"seeds: {{first: {first_seed}, count: {seeds}}}", "blackboard:", "  - {color: red, lift_height: 0.15}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _campaign_run(campaign_file: Path, out: Path, workers: int) -> dict[str, Any]:
    from bt_grasp.campaign.backend import warm_backend
    from bt_grasp.campaign.local import LocalEngine
    from bt_grasp.campaign.results import read_rows, results_path
    from bt_grasp.campaign.runner import run_campaign
    from bt_grasp.campaign.spec import load_campaign
    from bt_grasp.campaign.worker import KeepLogs

    campaign = load_campaign(campaign_file)
    t0 = time.perf_counter()
    run_campaign(campaign, out, lambda: LocalEngine(workers, warm_backend, out / "logs", KeepLogs.NONE))
    wall = time.perf_counter() - t0
    rows = read_rows(results_path(out, campaign.name))
    setups = sorted(r["setup_wall_s"] for r in rows)
    return {
        "episodes": len(rows),
        "successes": sum(1 for r in rows if r["success"]),
        "wall_s": round(wall, 1),
        "episodes_per_min": round(60 * len(rows) / wall, 2),
        # per-episode overhead of a warm worker: inputs loaded, world reset, tree wired, up to the first tick
        # (the first episode of each worker builds its world: listed apart)
        "setup_s_median_warm": round(statistics.median(setups[workers:]), 3) if len(setups) > workers else None,
        "setup_s_max_cold": round(max(setups), 3),
        "fingerprints": {r["episode"]: r["fingerprint"] for r in rows},
    }


def run_eval_bench(trees: list[Path], scene: Path, seeds: int, first_seed: int, workers: list[int]) -> dict[str, Any]:
    from bt_grasp.cli.bench_extra_cmd import run_pick_bench
    from bt_grasp.environment import machine_description
    from bt_grasp.scene_config import load_scene

    config = load_scene(scene)
    calibration = scene.parent / config.calibration if config.calibration else None
    report: dict[str, Any] = {"machine": machine_description(), "load_before": os.getloadavg(), "runs": {}}
    n = len(trees) * seeds
    t0 = time.perf_counter()
    pick = run_pick_bench(trees, scene, seeds, first_seed, calibration, None)
    wall = time.perf_counter() - t0
    report["runs"]["bench pick (one process, a world per episode)"] = {
        "episodes": n,
        "successes": sum(t["successes"] for t in pick["trees"].values()),
        "wall_s": round(wall, 1),
        "episodes_per_min": round(60 * n / wall, 2),
    }
    with tempfile.TemporaryDirectory(prefix="bt_grasp_bench_eval_") as tmp:
        campaign_file = _campaign_file(Path(tmp), trees, scene, seeds, first_seed)
        prints = []
        for w in workers:
            result = _campaign_run(campaign_file, Path(tmp) / f"w{w}", w)
            prints.append(result.pop("fingerprints"))
            report["runs"][f"eval run --workers {w}"] = result
    report["same_fingerprints_across_worker_counts"] = all(p == prints[0] for p in prints)
    report["load_after"] = os.getloadavg()
    return report


@bench_app.command("eval")
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
    """Episodes per minute, side by side: `bench pick`'s loop, then a campaign on each worker count."""
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
