"""Episodes per minute, side by side (`bt-grasp bench eval`): `bench pick`'s loop, then a campaign on each worker
count; also whether the run fingerprints agree across worker counts."""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import NotRequired, TypedDict

from bt_grasp.files.json_types import JsonValue


class EvalRun(TypedDict):
    """One way of running the episodes: how many, how fast."""

    episodes: int
    successes: int
    wall_s: float
    episodes_per_min: float
    setup_s_median_warm: NotRequired[float | None]  # a campaign's
    setup_s_max_cold: NotRequired[float]


class EvalReport(TypedDict):
    """``run_eval_bench``'s figures."""

    machine: str
    load_before: tuple[float, float, float]
    runs: dict[str, EvalRun]
    same_fingerprints_across_worker_counts: NotRequired[bool]
    load_after: NotRequired[tuple[float, float, float]]


def _seconds(value: JsonValue) -> float:
    """A results row's time column (a number: the worker wrote it)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"a time in a results row is a number, not {value!r}")
    return float(value)


def _campaign_file(folder: Path, trees: list[Path], scene: Path, seeds: int, first_seed: int) -> Path:
    path = folder / "bench.yaml"
    lines = ["name: bench", "trees:", *[f"  - {t.resolve()}" for t in trees], "scenes:", f"  - {scene.resolve()}",
             f"seeds: {{first: {first_seed}, count: {seeds}}}", "blackboard:", "  - {color: red, lift_height: 0.15}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _campaign_run(campaign_file: Path, out: Path, workers: int) -> tuple[EvalRun, dict[str, JsonValue]]:
    """The campaign's figures, and its episodes' fingerprints (episode -> fingerprint)."""
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
    setups = sorted(_seconds(r["setup_wall_s"]) for r in rows)
    figures: EvalRun = {
        "episodes": len(rows),
        "successes": sum(1 for r in rows if r["success"]),
        "wall_s": round(wall, 1),
        "episodes_per_min": round(60 * len(rows) / wall, 2),
        # per-episode overhead of a warm worker: inputs loaded, world built, tree wired, up to the first tick
        # (the first episode of each worker builds its world: listed apart)
        "setup_s_median_warm": round(statistics.median(setups[workers:]), 3) if len(setups) > workers else None,
        "setup_s_max_cold": round(max(setups), 3),
    }
    return figures, {str(r["episode"]): r["fingerprint"] for r in rows}


def run_eval_bench(trees: list[Path], scene: Path, seeds: int, first_seed: int, workers: list[int]) -> EvalReport:
    from bt_grasp.bench.pick import run_pick_bench
    from bt_grasp.process.environment import machine_description
    from bt_grasp.scene.format import load_scene

    config = load_scene(scene)
    calibration = scene.parent / config.calibration if config.calibration else None
    report: EvalReport = {"machine": machine_description(), "load_before": os.getloadavg(), "runs": {}}
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
            result, fingerprints = _campaign_run(campaign_file, Path(tmp) / f"w{w}", w)
            prints.append(fingerprints)
            report["runs"][f"eval run --workers {w}"] = result
    report["same_fingerprints_across_worker_counts"] = all(p == prints[0] for p in prints)
    report["load_after"] = os.getloadavg()
    return report
