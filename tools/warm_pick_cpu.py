"""CPU time of warm picks, which a machine shared with other work disturbs far less than wall time (issue 27).

    python tools/warm_pick_cpu.py picks [--n 5] [--fingerprint] [--log]
    python tools/warm_pick_cpu.py stages [--log]
    python tools/warm_pick_cpu.py log [--n 8]

``picks``: one warm-up pick, then ``--n`` picks of the same seed beside a warm renderer (``WarmWorlds``: what the
resident and a campaign worker run); prints the medians of the episode's set-up CPU (building the world and the
tree), the tick loop thread's CPU, the process's CPU during the run (every thread: OpenBLAS's, lavapipe's, the
log's feeder) and the tick loop's wall time. ``--fingerprint`` computes the run fingerprint as campaign workers do.

``log``: what ``--log`` costs the tick loop: after a warm-up with and without a log, ``--n`` picks without and
``--n`` with a log, alternating, in one process; prints both sides' medians of the CPU of the thread running
the episode (``Episode.run``: with a log also the recorder's set-up, the end frame and closing the file), the
process's CPU during the run (the writer process's own is not in it) and the tick loop's wall time, and each
one's increase with the log.

``stages``: ``bt-grasp bench budget`` with its stage clocks reading the tick loop thread's CPU time instead of
the wall clock (the floor stays wall time).

Both run with one OpenBLAS thread, as ``bt-grasp`` does. To compare with an older commit, unpack it
(``git archive OLD | tar -x -C /tmp/old``) and alternate ``PYTHONPATH=/tmp/old python tools/warm_pick_cpu.py ...``
with this tree's runs; the CHANGELOG's "Performance history" has figures taken that way.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bt_grasp.process.numeric_threads import use_one_blas_thread  # noqa: E402

use_one_blas_thread()  # as `bt-grasp` does, before numpy is imported

TREE, SCENE = ROOT / "trees" / "pick.xml", ROOT / "scenes" / "tabletop.yaml"


def picks(n: int, fingerprint: bool, log: bool) -> dict[str, float]:
    import tempfile

    from bt_grasp.episode import Episode, WarmWorlds, pick_request

    folder = Path(tempfile.mkdtemp(prefix="bt_grasp_cpu_"))
    worlds = WarmWorlds()

    def request(k: int):  # type: ignore[no-untyped-def]
        r = pick_request(TREE, SCENE, 0, calibration=None, log=folder / f"{k}.mcap" if log else None)
        return replace(r, fingerprint=True) if fingerprint else r

    Episode(request(0), worlds).run()  # imports, the renderer's start-up, first pictures: not measured
    rows = []
    for k in range(n):
        c0 = time.process_time()
        episode = Episode(request(k + 1), worlds)
        c1, t1 = time.process_time(), time.thread_time()
        result = episode.run()
        c2, t2 = time.process_time(), time.thread_time()
        rows.append({"setup_cpu_s": c1 - c0, "tick_loop_thread_cpu_s": t2 - t1, "run_process_cpu_s": c2 - c1,
                     "tick_loop_wall_s": result.wall_time_s, "ticks": result.ticks})
    return {key: round(statistics.median(r[key] for r in rows), 4) for key in rows[0]}


def log_cost(n: int) -> dict[str, object]:
    import tempfile

    from bt_grasp.episode import Episode, WarmWorlds, pick_request

    folder = Path(tempfile.mkdtemp(prefix="bt_grasp_cpu_"))
    worlds = WarmWorlds()

    def run(k: int, log: bool) -> dict[str, float]:
        episode = Episode(pick_request(TREE, SCENE, 0, calibration=None, log=folder / f"{k}.mcap" if log else None),
                          worlds)
        c1, t1 = time.process_time(), time.thread_time()
        result = episode.run()
        return {"run_thread_cpu_s": time.thread_time() - t1, "run_process_cpu_s": time.process_time() - c1,
                "tick_loop_wall_s": result.wall_time_s}

    run(0, True), run(0, False)  # imports, the renderer's start-up, the writer process: not measured
    rows: dict[bool, list[dict[str, float]]] = {False: [], True: []}
    for k in range(n):
        for log in (False, True):
            rows[log].append(run(k + 1, log))
    out: dict[str, object] = {}
    for key in rows[False][0]:
        without = statistics.median(r[key] for r in rows[False])
        with_log = statistics.median(r[key] for r in rows[True])
        out[key] = {"no_log": round(without, 4), "log": round(with_log, 4), "added_s": round(with_log - without, 4),
                    "added_pct": round(100.0 * (with_log / without - 1.0), 1)}
    return out


def stages(log: bool) -> dict[str, object]:
    from bt_grasp.bench.budget import run_budget_bench

    report = run_budget_bench(TREE, SCENE, 0, None, log, now=time.thread_time)
    return {"episode_thread_cpu_s": report["episode_wall_s"], "same_as_warmup": report["same_as_warmup"],
            "stages_thread_cpu_s": {s["stage"]: s["s"] for s in report["stages"]},
            "per_tick_us": report["tick_loop_overhead_us_per_tick"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=("picks", "stages", "log"))
    parser.add_argument("--n", type=int, default=5)
    parser.add_argument("--fingerprint", action="store_true")
    parser.add_argument("--log", action="store_true")
    args = parser.parse_args()
    if args.what == "picks":
        out: dict[str, object] = picks(args.n, args.fingerprint, args.log)
    elif args.what == "log":
        out = log_cost(args.n)
    else:
        out = stages(args.log)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
