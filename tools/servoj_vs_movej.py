"""servoJ streaming against moveJ paths, on the twin: which way should a planned trajectory reach a UR?

    python tools/servoj_vs_movej.py [--motions 8] [--seed 0]

A twin of ``scenes/tabletop.yaml`` is started; motions from the cell's home to seeded poses over the table are
planned as bt_grasp plans them (OMPL's path through collision-free waypoints, for the cell's 2F-85, in the planning
scene of the twin's cell file). Each is executed three ways with the unmodified ur_rtde library:

* **servoJ**: the path timed by ruckig under the cell's caps (``MotionGuard.fit``), one target per 8 ms controller
  period (``initPeriod``/``waitPeriod``), as ``UrArm`` streams it;
* **moveJ per waypoint**: ``moveJ(q, speed, acceleration)`` to each waypoint in turn, at the joint caps (the arm stops
  at every waypoint; between them UR's movej is linear in joint space, so it stays on the checked path);
* **moveJ path**: ``moveJ(path)`` with blend radii (UR's blended path): ur_rtde sends it as a program path
  (command 45), which the twin does not run (it says so); reported as such.

Measured per motion from the receive interface at 125 Hz: the time to arrive (within 1 mrad, every joint slower than
0.005 rad/s) and the largest distance (joint space, rad) of the arm from the planned, collision-checked path.
docs/real-cell.md has the figures.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import rtde_control
import rtde_receive

from bt_grasp.bench.twin_process import start_twin
from bt_grasp.cell.format import load_cell
from bt_grasp.cell.grippers import ROBOTIQ_2F85, robot_urdf_path_with
from bt_grasp.episode.cell_devices import guard_for
from bt_grasp.episode.cell_scene import scene_for_cell
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.planner import MotionPlanner, PlannerOptions
from bt_grasp.motion.planning_scene import PlanningScene
from bt_grasp.motion.trajectory import MotionLimits, Trajectory, time_parametrize

PERIOD_S = 0.008


def _deviation(samples: np.ndarray, path: np.ndarray) -> float:
    """Largest distance of any sample from the polyline through ``path`` (rad, joint space)."""
    a, b = path[:-1], path[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    worst = 0.0
    for q in samples:
        t = np.clip(np.einsum("ij,ij->i", q - a, ab) / denom, 0.0, 1.0)
        worst = max(worst, float(np.min(np.linalg.norm(a + t[:, None] * ab - q, axis=1))))
    return worst


class Sampler:
    """The arm's actual joints at 125 Hz in a thread of its own."""

    def __init__(self, receive: rtde_receive.RTDEReceiveInterface) -> None:
        self.receive = receive
        self.samples: list[np.ndarray] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            self.samples.append(np.array(self.receive.getActualQ()))
            time.sleep(PERIOD_S)

    def __enter__(self) -> Sampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def _arrived(receive: rtde_receive.RTDEReceiveInterface, goal: np.ndarray, timeout_s: float = 10.0) -> None:
    start = time.monotonic()
    while time.monotonic() - start < timeout_s:
        q, qd = np.array(receive.getActualQ()), np.array(receive.getActualQd())
        if np.max(np.abs(q - goal)) < 1e-3 and np.max(np.abs(qd)) < 0.005:
            return
        time.sleep(0.002)
    raise RuntimeError("the arm did not arrive")


def by_servoj(control: rtde_control.RTDEControlInterface, receive: rtde_receive.RTDEReceiveInterface,
              trajectory: Trajectory) -> tuple[float, np.ndarray]:
    start = time.monotonic()
    with Sampler(receive) as sampler:
        t = 0.0
        while t <= trajectory.duration_s + PERIOD_S:
            cycle = control.initPeriod()
            q, _, _ = trajectory.sample(t)
            control.servoJ(q.tolist(), 0.0, 0.0, PERIOD_S, 0.1, 300.0)
            control.waitPeriod(cycle)
            t += PERIOD_S
        _arrived(receive, trajectory.q[-1])
        elapsed = time.monotonic() - start
    control.servoStop(10.0)
    return elapsed, np.array(sampler.samples)


def by_movej(control: rtde_control.RTDEControlInterface, receive: rtde_receive.RTDEReceiveInterface,
             path: np.ndarray, speed: float, accel: float) -> tuple[float, np.ndarray]:
    start = time.monotonic()
    with Sampler(receive) as sampler:
        for q in path[1:]:
            assert control.moveJ(q.tolist(), speed, accel)
        _arrived(receive, path[-1])
        elapsed = time.monotonic() - start
    return elapsed, np.array(sampler.samples)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--motions", type=int, default=8)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="servoj_vs_movej_") as tmp:
        twin = start_twin("scenes/tabletop.yaml", Path(tmp))
        try:
            cell = load_cell(twin.cell_path)
            scene = PlanningScene.from_scene(scene_for_cell(cell))
            urdf = robot_urdf_path_with(ROBOTIQ_2F85.name)
            kin = ArmKinematics(urdf_path=urdf)
            guard = guard_for(cell, kin)
            planner = MotionPlanner(urdf_path=urdf)
            caps = MotionLimits(cell.arm.joint_speed_cap_rad_s, cell.arm.joint_accel_cap_rad_s2)
            home = np.array(cell.arm.home_q_rad)
            rng = np.random.default_rng(args.seed)
            receive = rtde_receive.RTDEReceiveInterface(twin.host)
            control = rtde_control.RTDEControlInterface(twin.host)
            rows: list[dict[str, float]] = []
            try:
                while len(rows) < args.motions:
                    T = kin.fk(home)
                    T[:3, 3] = [rng.uniform(0.35, 0.65), rng.uniform(-0.25, 0.25), rng.uniform(0.08, 0.3)]
                    plan = planner.plan_to_pose(home, T, scene, PlannerOptions(seed=int(rng.integers(1, 2**31))))
                    if not plan.ok or len(plan.path) < 2:
                        continue
                    path = np.asarray(plan.path)
                    fitted = guard.prepare(time_parametrize(path, caps, rate_hz=125.0, blend=True))
                    if isinstance(fitted, str):
                        continue
                    assert control.moveJ(home.tolist(), 1.0, 2.0)
                    servo_s, servo_q = by_servoj(control, receive, fitted)
                    assert control.moveJ(home.tolist(), 1.0, 2.0)
                    movej_s, movej_q = by_movej(control, receive, path, cell.arm.joint_speed_cap_rad_s,
                                                cell.arm.joint_accel_cap_rad_s2)
                    row = {"waypoints": len(path), "servoj_s": servo_s, "movej_s": movej_s,
                           "servoj_dev_rad": _deviation(servo_q, path), "movej_dev_rad": _deviation(movej_q, path),
                           "planned_dev_rad": fitted.max_path_deviation_rad}
                    rows.append(row)
                    print(f"motion {len(rows)}: {len(path)} waypoints; servoJ {servo_s:.2f} s, off the path "
                          f"{row['servoj_dev_rad'] * 1000:.1f} mrad (planned {row['planned_dev_rad'] * 1000:.1f}); "
                          f"moveJ per waypoint {movej_s:.2f} s, off {row['movej_dev_rad'] * 1000:.1f} mrad",
                          flush=True)
                blended = [[*q.tolist(), cell.arm.joint_speed_cap_rad_s, cell.arm.joint_accel_cap_rad_s2, 0.02]
                           for q in path[1:]]
                blended[-1][-1] = 0.0
                taken = control.moveJ(blended)
                print(f"moveJ(path) with blends: {'ran' if taken else 'refused'}; the twin's log: "
                      + next((line for line in twin.log().splitlines() if "unsupported by the twin" in line),
                             "(nothing)"))
            finally:
                if control.isConnected():
                    control.stopScript()
                control.disconnect()
                receive.disconnect()
            for key in ("servoj_s", "movej_s", "servoj_dev_rad", "movej_dev_rad"):
                values = [r[key] for r in rows]
                print(f"{key}: median {statistics.median(values):.4f}, max {max(values):.4f}")
        finally:
            twin.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
