"""``bt-grasp bench twin``: seeded picks on a real cell's code path against the twin, judged by the twin's physics.

For each seed a twin of the scene is started (``bench.twin_process``: its own process, real time, the seed's objects)
and the tree is run on its cell file in this process exactly as ``bt-grasp run TREE --cell CELL --yes`` runs it:
ur_rtde drives the twin's controller, the Robotiq client its gripper socket, the twin's camera frames go through a
pyrealsense2 software device, time is the wall clock. The twin's judge gives the verdict; the twin is stopped.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_grasp.bench.twin_process import start_twin


@dataclass(frozen=True)
class TwinPick:
    seed: int
    success: bool
    reason: str | None
    judged: str
    wall_s: float  # the run, from opening the cell to its result
    twin_start_s: float
    late_periods: int
    ticks: int


def run_twin_bench(tree: Path, scene: Path, seeds: int, first_seed: int = 0, log_dir: Path | None = None,
                   progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run ``tree`` on a twin of ``scene`` for each seed; the report (JSON-able)."""
    from bt_grasp.episode.cell_run import CellRunRequest, run_on_cell
    from bt_grasp.process.environment import machine_description

    rows: list[TwinPick] = []
    with tempfile.TemporaryDirectory(prefix="bt_grasp_bench_twin_") as tmp:
        for seed in range(first_seed, first_seed + seeds):
            twin = start_twin(scene, Path(tmp), seed=seed, salt=seed)
            try:
                log = None if log_dir is None else log_dir / f"twin-{tree.stem}-{seed}.mcap"
                request = CellRunRequest(tree=tree, cell=twin.cell_path, seed=seed, log=log,
                                         blackboard={"lift_height": 0.15},
                                         argv=("bt-grasp", "bench", "twin"))
                start = time.monotonic()
                outcome = run_on_cell(request, confirm=None)
                wall = time.monotonic() - start
            finally:
                twin.stop()
            result = outcome.result
            facts = "; ".join(detail for _c, _m, detail in result.judged.conditions)
            row = TwinPick(seed, result.success, result.reason, facts, wall, twin.started_in_s, outcome.overruns,
                           result.ticks)
            rows.append(row)
            if progress is not None:
                progress(f"seed {seed}: {'SUCCESS' if row.success else 'FAILURE'}"
                         + (f" ({row.reason})" if row.reason else "") + f", {wall:.1f} s, twin up in "
                         f"{twin.started_in_s:.1f} s, {row.late_periods} late periods; judge: {facts}")
    failures = Counter(r.reason or "GOAL_NOT_MET" for r in rows if not r.success)
    return {
        "tree": str(tree), "scene": str(scene), "seeds": seeds, "first_seed": first_seed,
        "successes": sum(r.success for r in rows), "runs": len(rows),
        "failures": dict(failures),
        "wall_s_median": statistics.median(r.wall_s for r in rows),
        "twin_start_s_median": statistics.median(r.twin_start_s for r in rows),
        "late_periods_median": statistics.median(r.late_periods for r in rows),
        "rows": [r.__dict__ for r in rows],
        "judged_by": "the twin's physics judge",
        "machine": machine_description(),
    }
