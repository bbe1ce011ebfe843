"""What recording, extra camera frames and the live server cost a pick, measured in one process.

    python tools/bench_log_overhead.py [--reps 3] [--seed 0] [--fresh] [--out FILE.json] [--configs NAME ...]
    python tools/bench_log_overhead.py --cli [--reps 8]     # whole one-off `bt-grasp run` commands

Runs the default pick (trees/pick.xml on scenes/tabletop.yaml, one warm world reused) in each configuration,
interleaved, ``--reps`` times: no log; --log (the format-2 log: every link's pose each tick, robot meshes,
camera frames at failures and at the end); --log --image-hz 2; --live with no viewer connected. Reports the
median wall time of the tick loop (world building excluded) and of the whole episode (inputs, world,
tree, ticks, judge; with ``--fresh`` a new world each time, as ``bt-grasp run`` does), the overheads against
no log, and the log's size per simulated minute. Figures depend on the machine and its load: the script
prints the load average too.

``--cli`` times what a user runs: whole ``bt-grasp run trees/pick.xml --scene scenes/tabletop.yaml
--calibration scenes/tabletop.calibration.yaml`` processes (start-up, renderer, run, log closed), without a
log, with ``--log``, with ``--log --image-hz 1`` and with ``--live 0``, interleaved, ``--reps`` times each.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bt_grasp.process.numeric_threads import use_one_blas_thread  # noqa: E402

use_one_blas_thread()  # as `bt-grasp run` does, before numpy is imported

from bt_grasp.episode.episode import Episode  # noqa: E402
from bt_grasp.episode.request import EpisodeRequest  # noqa: E402
from bt_grasp.episode.worlds import WarmWorlds  # noqa: E402

CONFIGS: dict[str, dict[str, Any]] = {
    "no log": {},
    "--log": {"log": True},
    "--log --image-hz 1": {"log": True, "image_hz": 1.0},
    "--log --image-hz 2": {"log": True, "image_hz": 2.0},
    "--live (no viewer)": {"live_port": 0},
}

CLI_CONFIGS: dict[str, list[str]] = {
    "no log": [],
    "--log": ["--log", "{log}"],
    "--log --image-hz 1": ["--log", "{log}", "--image-hz", "1"],
    "--live (no viewer)": ["--live", "0"],
}


def cli_main(reps: int, seed: int, out: Path | None) -> None:
    """Whole one-off ``bt-grasp run`` processes, interleaved; medians and overheads against no log."""
    import subprocess

    exe = Path(sys.executable).with_name("bt-grasp")
    base = [str(exe), "run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--seed", str(seed),
            "--calibration", "scenes/tabletop.calibration.yaml"]
    walls: dict[str, list[float]] = {name: [] for name in CLI_CONFIGS}
    sizes: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(reps + 1):  # the first round warms the disk caches; not counted
            for name, extra in CLI_CONFIGS.items():
                log = Path(tmp) / f"{rep}.mcap"
                cmd = base + [a.replace("{log}", str(log)) for a in extra]
                started = time.perf_counter()
                done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
                wall = time.perf_counter() - started
                if done.returncode != 0:
                    raise SystemExit(f"{name}: exit {done.returncode}: {done.stderr[-500:]}")
                if rep == 0:
                    continue
                walls[name].append(wall)
                if log.exists():
                    if name == "--log":
                        sizes.append(log.stat().st_size / 1e6)
                    log.unlink()
                print(f"{name:22s} rep {rep}: {wall:.2f} s", flush=True)
    base_s = statistics.median(walls["no log"])
    # each round ran every configuration back to back: the median of the rounds' own ratios is less moved by
    # the machine drifting over the minutes than the ratio of the medians
    rows = {name: {"wall_s_median": round(statistics.median(w), 3), "wall_s_all": [round(x, 3) for x in w],
                   "overhead_pct": round(100 * (statistics.median(w) / base_s - 1), 1),
                   "paired_overhead_pct": round(100 * statistics.median(
                       [x / b - 1 for x, b in zip(w, walls["no log"], strict=True)]), 1)}
            for name, w in walls.items()}
    report = {"command": " ".join(base[1:]), "reps": reps, "load_average": os.getloadavg(), "cpus": os.cpu_count(),
              "log_mb_median": round(statistics.median(sizes), 2) if sizes else None, "configs": rows}
    print(json.dumps(report, indent=2))
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(report, indent=2) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--fresh", action="store_true",
                        help="build a fresh world per run and time the whole episode (world, tree, ticks, judge)")
    parser.add_argument("--cli", action="store_true", help="time whole one-off `bt-grasp run` processes instead")
    parser.add_argument("--configs", nargs="+", choices=sorted(CONFIGS), default=None,
                        help="only these configurations (in-process mode; 'no log' is always measured)")
    args = parser.parse_args()
    if args.configs is not None:
        for name in [n for n in CONFIGS if n != "no log" and n not in args.configs]:
            del CONFIGS[name]
    if args.cli:
        cli_main(args.reps, args.seed, args.out)
        return
    worlds = None if args.fresh else WarmWorlds()
    episode_walls: dict[str, list[float]] = {name: [] for name in CONFIGS}
    walls: dict[str, list[float]] = {name: [] for name in CONFIGS}
    sizes: dict[str, list[float]] = {name: [] for name in CONFIGS}
    sim_s = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.reps + 1):  # the first round warms the world and the shaders; not counted
            for name, options in CONFIGS.items():
                opts = dict(options)
                log = Path(tmp) / f"{rep}-{len(walls[name])}.mcap" if opts.pop("log", False) else None
                request = EpisodeRequest(tree=ROOT / "trees/pick.xml", scene=ROOT / "scenes/tabletop.yaml",
                                         seed=args.seed, log=log, blackboard={"color": "red", "lift_height": 0.15},
                                         **opts)
                started = time.perf_counter()
                result = Episode(request, worlds).run()
                episode_s = time.perf_counter() - started
                if not result.success:
                    raise SystemExit(f"{name}: the pick failed ({result.reason}); figures would mean nothing")
                if rep == 0:
                    continue
                walls[name].append(result.wall_time_s)
                episode_walls[name].append(episode_s)
                sim_s = result.sim_time_s
                if log is not None:
                    sizes[name].append(log.stat().st_size / 1e6 / (result.sim_time_s / 60.0))
                    log.unlink()
                print(f"{name:22s} rep {rep}: {result.wall_time_s:.2f} s", flush=True)
    base = statistics.median(walls["no log"])
    rows = {}
    for name in CONFIGS:
        wall = statistics.median(walls[name])
        whole = statistics.median(episode_walls[name])
        rows[name] = {"wall_s_median": round(wall, 3), "wall_s_all": [round(w, 3) for w in walls[name]],
                      "overhead_pct": round(100 * (wall / base - 1), 1),
                      "episode_s_median": round(whole, 3),
                      "episode_overhead_pct": round(100 * (whole / statistics.median(episode_walls["no log"]) - 1), 1),
                      "mb_per_sim_minute": round(statistics.median(sizes[name]), 2) if sizes[name] else None}
    report = {"sim_time_s": round(sim_s, 2), "reps": args.reps, "load_average": os.getloadavg(),
              "cpus": os.cpu_count(), "configs": rows}
    print(json.dumps(report, indent=2))
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
