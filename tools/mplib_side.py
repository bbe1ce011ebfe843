"""Runs MPlib 0.2.1 on the problems `tools/mplib_compare.py` wrote; executed by that tool in MPlib's own venv.

Reads the problem file (JSON: the robot URDF, the tool link, the open finger positions, and per problem the
start joints, the goal tool pose in the base frame and the boxes of its scene), plans each with
``Planner.plan_pose`` at MPlib's defaults (20 IK seeds, RRTConnect with a 1 s limit, simplification, TOPP-RA at
0.1 s steps), and writes per problem: status, wall time of the call, and the joint waypoints it returned.
This file imports MPlib only: it never imports bt_grasp (its numpy<2 venv has no bt_grasp).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np


def main(problems_path: str, out_path: str, srdf_dir: str) -> None:
    import mplib
    from mplib.collision_detection import fcl

    spec = json.loads(Path(problems_path).read_text())
    urdf = Path(spec["urdf"])
    srdf = Path(srdf_dir) / (urdf.stem + "_mplib.srdf")
    if not srdf.is_file():  # MPlib samples the robot once to write its SRDF (disabled collision pairs)
        from mplib.urdf_utils import generate_srdf

        generated = Path(generate_srdf(str(urdf), "", verbose=False))
        srdf.write_text(generated.read_text())
    planner = mplib.Planner(str(urdf), spec["tool_link"], srdf=str(srdf))
    names = list(planner.user_joint_names)
    arm = [names.index(n) for n in spec["arm_joints"]]
    full = np.zeros(len(names))
    for name, value in spec["finger_positions"].items():
        full[names.index(name)] = value
    np.random.seed(int(spec["seed"]))
    mplib.set_global_seed(int(spec["seed"]))
    results = []
    for problem in spec["problems"]:
        for name in list(planner.planning_world.get_object_names()):
            planner.planning_world.remove_object(name)
        for box in problem["boxes"]:
            shape = fcl.CollisionObject(fcl.Box(np.asarray(box["size_m"], dtype=float)))
            pose = mplib.Pose(np.asarray(box["xyz_m"], dtype=float), np.asarray(box["quat_wxyz"], dtype=float))
            planner.planning_world.add_object(fcl.FCLObject(box["name"], pose, [shape], [mplib.Pose()]))
            for link in box.get("touch_links", []):  # the base link stands on the table
                planner.acm.set_entry(box["name"], link, True)
        qpos = full.copy()
        qpos[arm] = problem["q_start"]
        goal = mplib.Pose(np.asarray(problem["T_base_tcp_goal"], dtype=float))
        t0 = time.perf_counter()
        result = planner.plan_pose(goal, qpos, wrt_world=False)
        wall = time.perf_counter() - t0
        entry = {"index": problem["index"], "status": str(result["status"]), "wall_s": wall}
        if result["status"] == "Success":
            positions = np.asarray(result["position"], dtype=float)
            move = list(planner.move_group_joint_indices)
            entry["path"] = positions[:, [move.index(i) for i in arm]].tolist()
            entry["duration_s"] = float(result["duration"])
        results.append(entry)
    Path(out_path).write_text(json.dumps({"mplib": mplib.__version__, "joint_names": names, "results": results}))


if __name__ == "__main__":
    main(*sys.argv[1:4])
