"""The planning benchmark: a fixed, seeded set of tabletop problems planned and time-parametrised.

Each problem starts near home (or at a random collision-free configuration with the tool above the
table) and asks for a top-down tool pose above an object or at it (the object is then the scene's
allowed object), with 0-3 box obstacles standing on the table between start and goal. Times are wall
clock on the machine that runs it.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from typing import NotRequired, TypedDict

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import make_T
from bt_grasp.motion.collision import collision_checker
from bt_grasp.motion.kinematics import default_kinematics
from bt_grasp.motion.planner import PlannerOptions, PlanStatus, default_planner
from bt_grasp.motion.planning_scene import Box, PlanningScene, table_box
from bt_grasp.motion.trajectory import MotionLimits, time_parametrize
from bt_grasp.scene.format import Scene

log = logging.getLogger(__name__)

OBJECT_SIZE_M = (0.05, 0.05, 0.05)
#: an "at" goal puts the finger tips 5 mm above the table: plan those with a smaller table margin
AT_OBJECT_MARGIN_M = 0.002


class PlanSummary(TypedDict):
    """``PlanReport.summary``: the problem set's figures (times in ms, NaN when no problem gave one)."""

    problems: int
    seed: int
    planner: str
    success_rate: float
    plan_ms_median: float
    plan_ms_p95: float
    ik_ms_median: float
    traj_ms_median: float
    path_length_rad_median: float
    traj_duration_s_median: float
    direct_fraction: float
    statuses: dict[str, int]
    labelled_problems: int
    feasible_problems: int
    success_over_feasible: float | None
    machine: NotRequired[str]  # the command adds where it ran


@dataclass(frozen=True)
class BenchProblem:
    index: int
    kind: str  # "above" (pre-grasp) or "at" (grasp pose, the object allowed to touch the fingers)
    q_start: NDArray[np.float64]
    T_base_tcp_goal: NDArray[np.float64]
    target: Box  # the object the goal refers to
    obstacles: tuple[Box, ...]

    def scene(self, scene_config: Scene) -> PlanningScene:
        base = PlanningScene(table_box(scene_config), self.obstacles)
        return base.with_allowed_object(self.target) if self.kind == "at" else base.with_obstacles(self.target)

    def to_json(self) -> dict[str, object]:
        return {
            "index": self.index,
            "kind": self.kind,
            "q_start": self.q_start.tolist(),
            "T_base_tcp_goal": self.T_base_tcp_goal.tolist(),
            "target": {"name": self.target.name, "size_m": self.target.size_m, "xyz_m": self.target.xyz_m,
                       "quat_wxyz": self.target.quat_wxyz},
            "obstacles": [{"name": o.name, "size_m": o.size_m, "xyz_m": o.xyz_m, "quat_wxyz": o.quat_wxyz}
                          for o in self.obstacles],
        }


@dataclass(frozen=True)
class ProblemOutcome:
    index: int
    status: PlanStatus
    plan_ms: float
    ik_ms: float
    traj_ms: float = float("nan")
    path_length_rad: float = float("nan")
    traj_duration_s: float = float("nan")
    direct: bool = False  # the straight joint line was free: no search


@dataclass(frozen=True)
class BenchReport:
    problems: int
    seed: int
    planner: str
    outcomes: tuple[ProblemOutcome, ...] = field(repr=False)

    def _ok(self) -> list[ProblemOutcome]:
        return [o for o in self.outcomes if o.status is PlanStatus.OK]

    def summary(self) -> PlanSummary:
        ok = self._ok()
        statuses = Counter(o.status.value for o in self.outcomes)
        labels = feasibility_labels(self.seed)
        feasible = [o for o in self.outcomes if labels.get(o.index) is True]

        def pct(values: list[float], q: float) -> float:
            return round(float(np.percentile(values, q)), 3) if values else float("nan")

        plan = [o.plan_ms for o in ok]
        return {
            "problems": self.problems,
            "seed": self.seed,
            "planner": self.planner,
            "success_rate": round(len(ok) / self.problems, 4) if self.problems else 0.0,
            "plan_ms_median": pct(plan, 50),
            "plan_ms_p95": pct(plan, 95),
            "ik_ms_median": pct([o.ik_ms for o in self.outcomes], 50),
            "traj_ms_median": pct([o.traj_ms for o in ok], 50),
            "path_length_rad_median": pct([o.path_length_rad for o in ok], 50),
            "traj_duration_s_median": pct([o.traj_duration_s for o in ok], 50),
            "direct_fraction": round(sum(o.direct for o in ok) / len(ok), 4) if ok else 0.0,
            "statuses": dict(sorted(statuses.items())),
            # over the problems labelled feasible once by a larger-budget search (bench/data/bench_plan_labels.json)
            "labelled_problems": sum(1 for o in self.outcomes if o.index in labels),
            "feasible_problems": len(feasible),
            "success_over_feasible": round(sum(o.status is PlanStatus.OK for o in feasible) / len(feasible), 4)
            if feasible else None,
        }


def feasibility_labels(seed: int) -> dict[int, bool]:
    """Problem index -> feasible (True) or not proven (False), for the labelled problem-set seed; else {}."""
    import json
    from importlib.resources import files

    data = json.loads(files("bt_grasp.bench").joinpath("data/bench_plan_labels.json").read_text())
    if int(data["seed"]) != seed:
        return {}
    not_proven = set(data["not_proven"])
    return {i: i not in not_proven for i in range(int(data["labelled"]))}


def _random_start(rng: np.random.Generator, scene: PlanningScene, home: NDArray[np.float64]) -> NDArray[np.float64]:
    kin = default_kinematics()
    checker = collision_checker(scene, 0.01)
    for _ in range(1000):
        if rng.random() < 0.5:
            q = home + rng.uniform(-0.3, 0.3, 6)
        else:
            q = rng.uniform(-np.pi, np.pi, 6)
            q[2] = rng.uniform(-2.8, 2.8)
        if checker.is_valid(q) and kin.fk(q)[2, 3] > 0.1:
            return q
    raise RuntimeError("no collision-free start found in 1000 draws")


def make_problems(scene_config: Scene, count: int = 60, seed: int = 0) -> list[BenchProblem]:
    """A reproducible list of tabletop planning problems (same seed, same problems)."""
    rng = np.random.default_rng(seed)
    kin = default_kinematics()
    home = np.asarray(scene_config.robot.home_q_rad, dtype=float)
    table = PlanningScene(table_box(scene_config))
    problems = []
    for index in range(count):
        q_start = _random_start(rng, table, home)
        xy = np.array([rng.uniform(0.3, 0.65), rng.uniform(-0.3, 0.3)])
        yaw = rng.uniform(-np.pi / 2, np.pi / 2)
        c, s = np.cos(yaw), np.sin(yaw)
        R_obj = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        target = Box.at(f"object_{index}", OBJECT_SIZE_M, make_T(R_obj, [xy[0], xy[1], 0.025]))
        kind = "at" if rng.random() < 0.5 else "above"
        height = 0.025 if kind == "at" else 0.025 + rng.uniform(0.1, 0.2)
        y_axis = R_obj[:, 0]  # close across the object's x faces
        z_axis = np.array([0.0, 0.0, -1.0])
        T_goal = make_T(np.column_stack([np.cross(y_axis, z_axis), y_axis, z_axis]), [xy[0], xy[1], height])
        start_xy = kin.fk(q_start)[:2, 3]
        obstacles: list[Box] = []
        for k in range(int(rng.integers(0, 4))):
            for _ in range(20):
                f = rng.uniform(0.3, 0.7)
                centre = (1 - f) * start_xy + f * xy + rng.normal(0.0, 0.05, 2)
                size = (rng.uniform(0.04, 0.1), rng.uniform(0.04, 0.1), rng.uniform(0.15, 0.35))
                if np.linalg.norm(centre - xy) < 0.12 or not 0.2 < np.linalg.norm(centre) < 0.85:
                    continue
                box = Box(f"obstacle_{index}_{k}", size, (float(centre[0]), float(centre[1]), size[2] / 2))
                if collision_checker(table.with_obstacles(box), 0.01).is_valid(q_start):
                    obstacles.append(box)
                    break
        problems.append(BenchProblem(index, kind, q_start, T_goal, target, tuple(obstacles)))
    return problems


def run_plan_bench(scene_config: Scene, count: int = 60, seed: int = 0, options: PlannerOptions | None = None,
                   limits: MotionLimits | None = None) -> BenchReport:
    """Plan every problem (IK + OMPL + re-check) and time-parametrise every path."""
    opts = options or PlannerOptions()
    planner = default_planner()
    problems = make_problems(scene_config, count, seed)
    # warm up: model building and the first OMPL call are not part of any problem's time
    planner.plan_to_joints(problems[0].q_start, problems[0].q_start, PlanningScene(table_box(scene_config)), opts)
    outcomes = []
    at_opts = replace(opts, margin_m=min(opts.margin_m, AT_OBJECT_MARGIN_M))
    for problem in problems:
        scene = problem.scene(scene_config)
        problem_opts = at_opts if problem.kind == "at" else opts
        collision_checker(scene, problem_opts.margin_m)  # build the scene's collision model outside the timing
        t0 = time.perf_counter()
        result = planner.plan_to_pose(problem.q_start, problem.T_base_tcp_goal, scene, problem_opts)
        total_ms = (time.perf_counter() - t0) * 1e3
        if not result.ok:
            outcomes.append(ProblemOutcome(problem.index, result.status, total_ms, result.ik_time_s * 1e3))
            log.info("problem %d: %s (%s)", problem.index, result.status.value, result.message)
            continue
        t1 = time.perf_counter()
        trajectory = time_parametrize(result.path, limits)
        traj_ms = (time.perf_counter() - t1) * 1e3
        outcomes.append(ProblemOutcome(problem.index, result.status, total_ms, result.ik_time_s * 1e3, traj_ms,
                                       result.path_length_rad, trajectory.duration_s, result.planner == "direct"))
    return BenchReport(count, seed, opts.planner, tuple(outcomes))
