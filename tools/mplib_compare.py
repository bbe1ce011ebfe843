"""MPlib 0.2.1 beside bt_grasp's planner on the problems of `bt-grasp bench plan`, in one run, as peers.

    python tools/mplib_compare.py [--problems 60] [--seed 0] [--rounds 1] [--venv out/mplib-venv] [--json]

MPlib needs numpy<2, so it lives in its own venv (made here on first use, under out/, never committed):
this tool writes the problem set, plans every problem with bt_grasp (``plan_to_pose`` + time parametrisation,
as `bench plan` times it), runs ``tools/mplib_side.py`` in MPlib's venv on the same problems (``plan_pose`` at
its defaults), then checks **both** planners' paths in bt_grasp's collision checker at fine resolution (every
joint step <= 0.01 rad, no margin, the fingers open, within the joint limits, ending at the goal pose within
1 mm / 0.01 rad). It reports, per planner: solved, valid paths, total and median time; and the time ratio.

The scene each planner sees is the same boxes: the table (the base link may touch it), the obstacles, and the
target box when the goal is above it; for a goal *at* the object (fingers around it) the target is left out of
MPlib's world (it cannot allow only the fingers to touch it) and checked by bt_grasp's checker with only the
fingers allowed to touch it, as bt_grasp plans it.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MPLIB = "mplib==0.2.1"
GOAL_TOLERANCE_M = 1e-3
GOAL_TOLERANCE_RAD = 1e-2


def ensure_venv(venv: Path) -> Path:
    """MPlib's own venv (numpy<2), made once; its python."""
    python = venv / "bin" / "python"
    probe = [str(python), "-c", "import mplib, sys; sys.exit(mplib.__version__ != '0.2.1')"]
    if python.exists() and subprocess.run(probe, capture_output=True).returncode == 0:
        return python
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(python), "-m", "pip", "install", "-q", MPLIB, "numpy<2"], check=True)
    return python


def _box_json(box: Any) -> dict[str, Any]:
    return {"name": box.name, "size_m": list(box.size_m), "xyz_m": list(box.xyz_m),
            "quat_wxyz": list(box.quat_wxyz), "touch_links": list(box.touch_links)}


def main() -> int:
    from bt_grasp.bench.plan import AT_OBJECT_MARGIN_M, feasibility_labels, make_problems
    from bt_grasp.geometry import rotation_angle_rad
    from bt_grasp.motion.collision import FINE_RESOLUTION_RAD, collision_checker
    from bt_grasp.motion.kinematics import default_kinematics
    from bt_grasp.motion.planner import PlannerOptions, default_planner
    from bt_grasp.motion.planning_scene import PlanningScene, table_box
    from bt_grasp.motion.trajectory import time_parametrize
    from bt_grasp.process.environment import machine_description
    from bt_grasp.robot_description import ARM_JOINTS, FINGER_JOINT, MAX_OPENING_M, MIMIC_FINGER_JOINT, robot_urdf_path
    from bt_grasp.scene.format import load_scene

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--problems", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=1, help="plan the problem set this many times with each")
    parser.add_argument("--scene", type=Path, default=ROOT / "scenes/tabletop.yaml")
    parser.add_argument("--venv", type=Path, default=ROOT / "out/mplib-venv")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    python = ensure_venv(args.venv)
    work = args.venv.parent / "mplib-compare"
    work.mkdir(parents=True, exist_ok=True)
    config = load_scene(args.scene)
    problems = make_problems(config, args.problems, args.seed)
    table = table_box(config)
    kin = default_kinematics()

    # the same problems for MPlib; its URDF loader joins mesh paths to the URDF's folder, so the copy it reads
    # names the meshes relative to itself
    import os
    import re

    urdf_copy = work / "robot.urdf"
    text = robot_urdf_path().read_text()
    urdf_copy.write_text(re.sub(r'filename="(/[^"]+)"',
                                lambda m: f'filename="{os.path.relpath(m.group(1), work)}"', text))
    spec = {
        "urdf": str(urdf_copy), "tool_link": "tcp", "arm_joints": list(ARM_JOINTS), "seed": args.seed,
        "finger_positions": {FINGER_JOINT: MAX_OPENING_M / 2, MIMIC_FINGER_JOINT: MAX_OPENING_M / 2},
        "problems": [{
            "index": p.index, "q_start": p.q_start.tolist(), "T_base_tcp_goal": p.T_base_tcp_goal.tolist(),
            "boxes": [_box_json(b) for b in (table, *p.obstacles, *((p.target,) if p.kind == "above" else ()))],
        } for p in problems],
    }
    (work / "problems.json").write_text(json.dumps(spec))

    # bt_grasp: as `bench plan` plans and times them
    planner, opts = default_planner(), PlannerOptions()
    at_opts = replace(opts, margin_m=min(opts.margin_m, AT_OBJECT_MARGIN_M))
    planner.plan_to_joints(problems[0].q_start, problems[0].q_start, PlanningScene(table), opts)  # warm-up
    ours: dict[int, list[dict[str, Any]]] = {p.index: [] for p in problems}
    for _ in range(args.rounds):
        for p in problems:
            scene = p.scene(config)
            o = at_opts if p.kind == "at" else opts
            collision_checker(scene, o.margin_m)  # the scene's model is built outside the timing, as in bench plan
            t0 = time.perf_counter()
            result = planner.plan_to_pose(p.q_start, p.T_base_tcp_goal, scene, o)
            path = None
            if result.ok:
                time_parametrize(result.path)
                path = np.asarray(result.path, dtype=float)
            ours[p.index].append({"ok": result.ok, "status": result.status.value,
                                  "wall_s": time.perf_counter() - t0, "path": path})

    # MPlib: the same problems, in its venv
    theirs: dict[int, list[dict[str, Any]]] = {p.index: [] for p in problems}
    mplib_version = ""
    for r in range(args.rounds):
        out = work / f"mplib_round{r}.json"
        side = subprocess.run([str(python), str(ROOT / "tools/mplib_side.py"), str(work / "problems.json"),
                               str(out), str(work)], cwd=work, capture_output=True, text=True)
        if side.returncode != 0:  # MPlib prints its own notes on stdout: shown only when it failed
            raise SystemExit(f"MPlib's run failed ({side.returncode}):\n{side.stdout[-2000:]}\n{side.stderr[-2000:]}")
        data = json.loads(out.read_text())
        mplib_version = data["mplib"]
        for entry in data["results"]:
            path = np.asarray(entry["path"], dtype=float) if "path" in entry else None
            theirs[entry["index"]].append({"ok": entry["status"] == "Success", "status": entry["status"],
                                           "wall_s": entry["wall_s"], "path": path})

    def valid(p: Any, path: np.ndarray | None) -> tuple[bool, str]:
        if path is None or len(path) == 0:
            return False, "no path"
        if not np.allclose(path[0], p.q_start, atol=1e-4):
            return False, "does not start at the start"
        check = collision_checker(p.scene(config), 0.0).check_path(path, FINE_RESOLUTION_RAD)
        if not check.ok:
            return False, f"invalid state after segment {check.first_invalid_segment}"
        T = kin.fk(path[-1])
        err_m = float(np.linalg.norm(T[:3, 3] - p.T_base_tcp_goal[:3, 3]))
        err_rad = rotation_angle_rad(T[:3, :3], p.T_base_tcp_goal[:3, :3])
        if err_m > GOAL_TOLERANCE_M or err_rad > GOAL_TOLERANCE_RAD:
            return False, f"ends {err_m * 1e3:.1f} mm / {err_rad:.3f} rad from the goal"
        return True, ""

    labels = feasibility_labels(args.seed) if args.problems <= 60 else {}
    report: dict[str, Any] = {"machine": machine_description(), "problems": len(problems), "rounds": args.rounds,
                              "mplib": mplib_version, "planners": {}}
    invalid_examples: dict[str, list[str]] = {}
    for name, runs in (("bt_grasp", ours), ("mplib", theirs)):
        attempts = [(p, r) for p in problems for r in runs[p.index]]
        solved = [(p, r) for p, r in attempts if r["ok"]]
        checks = [(p, valid(p, r["path"])) for p, r in solved]
        n_valid = sum(1 for _, (ok, _why) in checks if ok)
        invalid_examples[name] = [f"problem {p.index}: {why}" for p, (ok, why) in checks if not ok][:10]
        walls = [r["wall_s"] for _, r in attempts]
        feasible = [(p, r) for p, r in attempts if labels.get(p.index) is True]
        report["planners"][name] = {
            "attempts": len(attempts), "solved": len(solved), "valid_paths": n_valid,
            "solved_feasible": f"{sum(1 for _, r in feasible if r['ok'])}/{len(feasible)}" if labels else None,
            "total_s": round(sum(walls), 3),
            "median_ms": round(1e3 * statistics.median(walls), 1),
            "p95_ms": round(1e3 * float(np.percentile(walls, 95)), 1),
            "statuses": dict(sorted({r["status"]: 0 for _, r in attempts}.items())),
        }
        for _, r in attempts:
            report["planners"][name]["statuses"][r["status"]] += 1
    report["invalid_examples"] = invalid_examples
    rows = []  # per problem and round, both planners: what each returned and whether its path checks out
    for p in problems:
        for k in range(args.rounds):
            row: dict[str, Any] = {"index": p.index, "kind": p.kind, "obstacles": len(p.obstacles),
                                   "label": labels.get(p.index)}
            for name, runs in (("bt_grasp", ours), ("mplib", theirs)):
                r = runs[p.index][k]
                ok, why = valid(p, r["path"]) if r["ok"] else (False, "")
                row[name] = {"status": r["status"], "ms": round(1e3 * r["wall_s"], 1), "valid": ok, "why": why}
            rows.append(row)
    (work / "rows.json").write_text(json.dumps(rows, indent=1))
    ours_total = report["planners"]["bt_grasp"]["total_s"]
    theirs_total = report["planners"]["mplib"]["total_s"]
    report["time_ratio_bt_grasp_over_mplib"] = round(ours_total / theirs_total, 3) if theirs_total else math.nan
    if args.json:
        print(json.dumps(report, indent=1))
        return 0
    print(f"{report['machine']}; {len(problems)} problems x {args.rounds} round(s); MPlib {mplib_version}")
    for name, r in report["planners"].items():
        print(f"{name:9s} solved {r['solved']}/{r['attempts']} (feasible: {r['solved_feasible']}), valid paths "
              f"{r['valid_paths']}, total {r['total_s']} s, median {r['median_ms']} ms, p95 {r['p95_ms']} ms; "
              f"{r['statuses']}")
        for line in invalid_examples[name]:
            print(f"          invalid: {line}")
    print(f"time ratio bt_grasp / MPlib (total): {report['time_ratio_bt_grasp_over_mplib']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
