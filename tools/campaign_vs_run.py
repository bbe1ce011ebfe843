"""A campaign and `bt-grasp run` agree episode for episode: every shipped task with every shipped fault plan.

    python tools/campaign_vs_run.py OUT [--seeds 0,1] [--task pick ...] [--plan object_nudge ...] [--workers 2]

For every shipped task (``bt_grasp.bench.tasks.TASKS``: ``trees/T.xml`` on ``scenes/T.yaml``, its tick limit) it
writes one campaign file (``OUT/T.campaign.yaml``: the task's tree and scene, every chosen fault plan of
``faults/``, the seeds, no ``blackboard`` key: the campaign's default) and runs it with ``bt-grasp eval run``;
then it runs each of the same episodes with ``bt-grasp run trees/T.xml --scene scenes/T.yaml --seed S --faults
faults/P.yaml --max-ticks M --summary-json J`` (nothing else: the user's command) and compares, per episode, what
:func:`facts` reads of a results row and of a run's summary: the tick count, the outcome (success, reason, failed
leaf), every fault's firing (label, tick, the leaf that armed it, the object a push hit and whether the tree
touched it) and every object's final pose (to 1e-6). A fault plan the tree cannot take (an ``on_leaf`` naming no
leaf of it) is refused by both, with the same sentence: that counts as agreeing too.

Prints one line per episode that differs, then the figure (episodes compared, how many agree); exit 0 when every
one agrees. ``tests/campaign/test_campaign_vs_run.py`` runs the same comparison for pick and stack with
object_nudge, frame_drop and gripper_slip at seed 0 in ``make test``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
#: final object poses are compared to this many decimals (the run fingerprint's resolution)
POSE_DECIMALS = 6


def facts(record: Mapping[str, Any]) -> dict[str, Any]:
    """What must agree, read from a campaign's results row or from `bt-grasp run --summary-json`'s summary (the two
    name the outcome's reason differently: ``failure_reason`` in a row, ``reason`` in a summary)."""
    judge = record.get("judge") or {}
    poses = judge.get("object_poses") or {}
    return {
        "ticks": record.get("ticks"),
        "success": record.get("success"),
        "reason": record.get("failure_reason", record.get("reason")),
        "failed_path": record.get("failed_path"),
        "faults": [(f.get("label"), f.get("tick"), f.get("leaf"), f.get("target"), f.get("target_touched"))
                   for f in record.get("faults") or []],
        "faults_fired": record.get("faults_fired"),
        "final_poses": {name: [[round(float(v), POSE_DECIMALS) for v in row] for row in pose]
                        for name, pose in sorted(poses.items())},
    }


def differences(a: Mapping[str, Any], b: Mapping[str, Any]) -> list[str]:
    """The facts that differ (``name: a != b``; poses by object name)."""
    out = []
    for key in a:
        if a[key] == b.get(key):
            continue
        if key == "final_poses":
            moved = sorted(n for n in set(a[key]) | set(b[key]) if a[key].get(n) != b[key].get(n))
            out.append(f"final poses of {', '.join(moved)}")
        else:
            out.append(f"{key}: {a[key]!r} != {b.get(key)!r}")
    return out


def _bt(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    code = "import sys; sys.argv = ['bt-grasp', *sys.argv[1:]]; from bt_grasp.cli.main import main; main()"
    return subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, capture_output=True, text=True, check=False)


def _campaign(out: Path, name: str, tree: Path, scene: Path, plan: Path, seeds: list[int], max_ticks: int,
              workers: int) -> tuple[dict[int, dict[str, Any]], str]:
    """One task with one fault plan as a campaign: rows by seed, or the refusal's sentence."""
    folder = out / f"{name}__{plan.stem}"
    folder.mkdir(parents=True, exist_ok=True)
    campaign = folder / "campaign.yaml"
    campaign.write_text(json.dumps({"name": f"{name}__{plan.stem}", "trees": [str(tree)], "scenes": [str(scene)],
                                    "seeds": seeds, "fault_plans": [str(plan)], "max_ticks": max_ticks}))
    proc = _bt(["eval", "run", str(campaign), "--out", str(folder / "results"), "--workers", str(workers),
                "--keep-logs", "none", "--no-parquet"], ROOT)
    if proc.returncode != 0:
        return {}, _refusal(proc.stderr)
    rows = [json.loads(line) for line in (folder / "results" / f"{name}__{plan.stem}.jsonl").read_text().splitlines()]
    return {int(r["seed"]): r for r in rows}, ""


def _run(out: Path, name: str, tree: Path, scene: Path, plan: Path, seed: int, *, max_ticks: int
         ) -> tuple[dict[str, Any] | None, str]:
    summary = out / f"{name}__{plan.stem}" / f"run-seed{seed}.json"
    summary.parent.mkdir(parents=True, exist_ok=True)
    proc = _bt(["run", str(tree), "--scene", str(scene), "--seed", str(seed), "--faults", str(plan), "--max-ticks",
                str(max_ticks), "--summary-json", str(summary), "--quiet"], ROOT)
    if proc.returncode == 2:
        return None, _refusal(proc.stderr)
    return json.loads(summary.read_text()), ""


def _refusal(stderr: str) -> str:
    """The refusal's reason, without the file that names it (a campaign file names itself first)."""
    line = stderr.strip().splitlines()[-1] if stderr.strip() else ""
    return line.split(": ")[-1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--task", action="append", default=[])
    parser.add_argument("--plan", action="append", default=[])
    parser.add_argument("--workers", type=int, default=1, help="campaign workers (and `run`s side by side)")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from bt_grasp.bench.tasks import TASKS

    seeds = [int(s) for s in args.seeds.split(",")]
    tasks = [t for t in TASKS if not args.task or t.name in args.task]
    plans = sorted(p for p in (ROOT / "faults").glob("*.yaml") if not args.plan or p.stem in args.plan)
    out = args.out.resolve()
    compared = agreed = refused = 0
    for task in tasks:
        tree, scene = task.paths(ROOT)
        for plan in plans:
            rows, campaign_refusal = _campaign(out, task.name, tree, scene, plan, seeds, task.max_ticks, args.workers)
            with ThreadPoolExecutor(max(1, args.workers)) as pool:
                runs = list(pool.map(partial(_run, out, task.name, tree, scene, plan, max_ticks=task.max_ticks),
                                     seeds))
            for seed, (summary, run_refusal) in zip(seeds, runs, strict=True):
                compared += 1
                what = f"{task.name} / {plan.stem} / seed {seed}"
                if summary is None or campaign_refusal:
                    same = summary is None and bool(campaign_refusal) and run_refusal == campaign_refusal
                    refused += same
                    agreed += same
                    if not same:
                        print(f"DIFFERS {what}: refused by {'run' if summary is None else 'the campaign'} only "
                              f"({run_refusal or campaign_refusal})")
                    continue
                found = differences(facts(rows[seed]), facts(summary))
                agreed += not found
                print(f"{'DIFFERS' if found else 'same   '} {what}" + (f": {'; '.join(found)}" if found else
                      f" ({summary['ticks']} ticks, {'success' if summary['success'] else summary['reason']})"),
                      flush=True)
    print(f"{len(tasks)} tasks x {len(plans)} fault plans x {len(seeds)} seeds = {compared} episodes: {agreed} agree "
          f"({refused} of them refused by both with the same sentence)")
    return 0 if agreed == compared else 1


if __name__ == "__main__":
    raise SystemExit(main())
