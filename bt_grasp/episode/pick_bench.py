"""Seeded picks judged by physics, per tree (`bt-grasp bench pick`): success, times, plan calls, planning time."""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path
from typing import Any

from bt_grasp.environment import machine_description
from bt_grasp.interfaces import Mount


def run_pick_bench(
    trees: list[Path], scene: Path, seeds: int, first_seed: int, calibration: Path | None, log_dir: Path | None,
    warm: bool = False,
) -> dict[str, Any]:
    from bt_grasp.episode import (
        EpisodeResult,
        FreshWorlds,
        WarmWorlds,
        WorldSource,
        pick_request,
        run_episode,
    )
    from bt_grasp.episode.calibration import calibrate_in_sim
    from bt_grasp.perception.calibration_file import save_calibration

    work = Path(tempfile.mkdtemp(prefix="bt_grasp_bench_"))
    if calibration is None:
        calibration = save_calibration(
            calibrate_in_sim(scene, Mount.EYE_TO_HAND, first_seed).run.calibration, work / "calibration.yaml"
        )
    report: dict[str, Any] = {
        "machine": machine_description(), "scene": str(scene), "calibration": str(calibration), "trees": {}
    }
    worlds: WorldSource = WarmWorlds() if warm else FreshWorlds()
    report["worlds"] = ("warm (a renderer kept warm; each episode's world built afresh)" if warm
                        else "fresh (a new world per episode)")
    for tree in trees:
        runs: list[EpisodeResult] = []
        for seed in range(first_seed, first_seed + seeds):
            log = (log_dir / f"{tree.stem}_seed{seed}.mcap") if log_dir is not None else None
            runs.append(run_episode(pick_request(tree, scene, seed, calibration=calibration, log=log), worlds=worlds))
        ok = [r for r in runs if r.success]
        report["trees"][str(tree)] = {
            "runs": len(runs),
            "successes": len(ok),
            "success_rate": len(ok) / len(runs),
            "failures": {r.seed: f"{r.reason} ({r.failed_leaf})" for r in runs if not r.success},
            "sim_time_s_median": round(statistics.median(r.sim_time_s for r in runs), 3),
            "wall_time_s_median": round(statistics.median(r.wall_time_s for r in runs), 3),
            "ticks_median": statistics.median(r.ticks for r in runs),
            "retries_total": sum(sum(r.retries.values()) for r in runs),
            "plan_calls_per_pick_mean": round(statistics.mean(r.planning.calls for r in runs), 2),
            "plan_pose_calls_per_pick_mean": round(statistics.mean(r.planning.pose_calls for r in runs), 2),
            "plan_wall_s_per_pick_median": round(statistics.median(r.planning.wall_s for r in runs), 4),
            "plan_wall_s_per_pick_mean": round(statistics.mean(r.planning.wall_s for r in runs), 4),
        }
    return report
