"""Joint-space motion planning with OMPL 2 (nanobind bindings) in a planning scene.

``plan_to_joints`` plans from a start configuration to a goal configuration; ``plan_to_pose`` first
solves IK for a tool pose (several distinct, collision-free solutions become the goal states, so the
planner picks whichever it reaches) and then plans. Both return a :class:`PlanResult` whose status says
what went wrong; no bad request raises.

Collision checking along edges: OMPL's motion validator checks states at most
``edge_resolution_rad`` apart (L2 in joint space, hence also on every joint); the simplified path is then
re-checked at ``final_resolution_rad`` (max joint step, 0.01 rad by default) before it is returned.

Reproducibility: ``ompl.util.RNG.setSeed(seed)`` reseeds OMPL's seed generator before every plan, and
every OMPL object that draws numbers is created after it, so the same request and seed give the same
path (OMPL logs "Random number generation already started" on reseeding; it reseeds all the same).
"""

from __future__ import annotations

import enum
import logging
import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from bt_grasp.geometry import Mat4
from bt_grasp.motion.collision import FINE_RESOLUTION_RAD, CollisionChecker, collision_checker
from bt_grasp.motion.kinematics import IKStatus, default_kinematics
from bt_grasp.motion.planning_scene import PlanningScene
from bt_grasp.robot_description import MAX_OPENING_M

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]

PLANNERS: dict[str, Callable[[ob.SpaceInformation], ob.Planner]] = {
    "RRTConnect": og.RRTConnect,
    "RRT": og.RRT,
    "RRTstar": og.RRTstar,
    "InformedRRTstar": og.InformedRRTstar,
    "SORRTstar": og.SORRTstar,
    "PRM": og.PRM,
    "PRMstar": og.PRMstar,
    "BITstar": og.BITstar,
    "AORRTC": og.AORRTC,
}


class PlanStatus(enum.Enum):
    OK = "ok"
    IK_UNREACHABLE = "ik_unreachable"  # no IK solution for the goal pose
    START_IN_COLLISION = "start_in_collision"  # or within the margin of the scene
    GOAL_IN_COLLISION = "goal_in_collision"  # every IK solution (or the goal configuration) collides
    NO_PATH = "no_path"  # the planner gave up, or its path failed the fine re-check
    INVALID_INPUT = "invalid_input"  # NaN, wrong shape, out of limits, bad options, unknown planner
    TIMEOUT = "timeout"  # no exact solution within the time limit


@dataclass(frozen=True)
class PlannerOptions:
    """How to plan. Times are wall-clock seconds of computation, not simulated time."""

    planner: str = "RRTConnect"  # a key of PLANNERS
    time_limit_s: float = 1.0  # for the planner's search (asymptotically optimal planners use all of it)
    seed: int = 1  # OMPL's RNG seed and the IK seeds' generator (OMPL treats 0 as "random": avoid it)
    simplify: str = "shortcut"  # "none" | "shortcut" (bounded, ~ms) | "full" (OMPL's simplifySolution)
    simplify_time_s: float = 0.5  # time given to "full" simplification (OMPL may overrun it)
    edge_resolution_rad: float = 0.025  # collision checks along edges during the search
    final_resolution_rad: float = FINE_RESOLUTION_RAD  # re-check of the returned path
    margin_m: float = 0.01  # minimum clearance to scene shapes (not applied to self-collision)
    range_rad: float | None = 1.0  # the tree planners' step size; None lets OMPL choose (~6 rad here)
    joint_window_rad: float | None = math.pi  # search only within this of the start/goal span per joint
    ik_seeds: int = 10  # IK starts for plan_to_pose (q_start first)
    max_goal_configs: int = 3  # distinct collision-free IK solutions handed to the planner

    def problem(self) -> str | None:
        """Why these options are unusable, or None."""
        if self.planner not in PLANNERS:
            return f"unknown planner '{self.planner}'; known: {', '.join(PLANNERS)}"
        for name in ("time_limit_s", "edge_resolution_rad", "final_resolution_rad", "simplify_time_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                return f"{name} must be a positive number, got {value}"
        if not (math.isfinite(self.margin_m) and self.margin_m >= 0):
            return f"margin_m must be >= 0, got {self.margin_m}"
        if self.simplify not in ("none", "shortcut", "full"):
            return f"simplify must be 'none', 'shortcut' or 'full', got '{self.simplify}'"
        if self.ik_seeds < 1 or self.max_goal_configs < 1:
            return "ik_seeds and max_goal_configs must be >= 1"
        if self.seed < 1:
            return "seed must be >= 1 (OMPL reads 0 as 'seed from the clock')"
        return None


@dataclass(frozen=True)
class PlanResult:
    """A planned joint path (N, 6) from the start to a goal configuration, or why there is none."""

    status: PlanStatus
    path: Vec = field(default_factory=lambda: np.zeros((0, 6)))
    planning_time_s: float = 0.0  # search + simplification + fine re-check
    ik_time_s: float = 0.0
    simplify_time_s: float = 0.0
    planner: str = ""
    message: str = ""
    goal_q: Vec | None = None

    @property
    def ok(self) -> bool:
        return self.status is PlanStatus.OK

    @property
    def path_length_rad(self) -> float:
        """Euclidean joint-space length of the path."""
        if len(self.path) < 2:
            return 0.0
        return float(np.sum(np.linalg.norm(np.diff(self.path, axis=0), axis=1)))


def _fail(status: PlanStatus, message: str, **kw: float | str) -> PlanResult:
    log.info("plan failed: %s: %s", status.value, message)
    return PlanResult(status=status, message=message, **kw)  # type: ignore[arg-type]


def _valid_q(q: NDArray[np.float64] | None) -> Vec | None:
    if q is None:
        return None
    a = np.asarray(q, dtype=float).reshape(-1)
    return a if a.shape == (6,) and np.all(np.isfinite(a)) else None


@contextmanager
def _ompl_console_silenced() -> Iterator[None]:
    """OMPL writes Info/Debug lines straight to the console; keep them out for one call."""
    ou.noOutputHandler()
    try:
        yield
    finally:
        ou.restorePreviousOutputHandler()


class MotionPlanner:
    """Plans arm motions for a gripper opening (the collision model's fingers sit at that opening)."""

    def __init__(self, opening_m: float = MAX_OPENING_M) -> None:
        self.opening_m = float(opening_m)
        self.kin = default_kinematics(self.opening_m)

    def checker(self, scene: PlanningScene, margin_m: float) -> CollisionChecker:
        return collision_checker(scene, float(margin_m), self.opening_m)

    # --- pose goals ---------------------------------------------------------------------------------
    def plan_to_pose(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                     options: PlannerOptions | None = None) -> PlanResult:
        """IK for the tcp pose (several collision-free solutions), then a joint-space plan to any of them."""
        opts = options or PlannerOptions()
        problem = opts.problem()
        q0 = _valid_q(q_start)
        if problem is not None or q0 is None:
            return _fail(PlanStatus.INVALID_INPUT, problem or f"bad start configuration {q_start!r}")
        t0 = time.perf_counter()
        rng = np.random.default_rng(opts.seed)
        # a few more solutions than goals: some may collide (IK stops once it has that many)
        solutions, best = self.kin.ik_solutions(T_base_tcp_goal, q0, seeds=opts.ik_seeds, rng=rng,
                                                max_solutions=2 * opts.max_goal_configs)
        ik_time = time.perf_counter() - t0
        if best.status is IKStatus.INVALID_INPUT:
            return _fail(PlanStatus.INVALID_INPUT, "the goal pose is not a finite rigid transform",
                         ik_time_s=ik_time)
        if not solutions:
            return _fail(PlanStatus.IK_UNREACHABLE,
                         f"no IK solution (best error {best.position_error_m * 1e3:.1f} mm, "
                         f"{np.rad2deg(best.rotation_error_rad):.2f} deg)", ik_time_s=ik_time)
        checker = self.checker(scene, opts.margin_m)
        goals = [q for q in solutions if checker.is_valid(q)][: opts.max_goal_configs]
        ik_time = time.perf_counter() - t0
        if not goals:
            pairs = checker.colliding_pairs(solutions[0])
            return _fail(PlanStatus.GOAL_IN_COLLISION,
                         f"all {len(solutions)} IK solutions collide (closest: {pairs or 'within margin'})",
                         ik_time_s=ik_time)
        result = self._plan(q0, goals, checker, opts)
        return _with(result, ik_time_s=ik_time)

    # --- joint goals --------------------------------------------------------------------------------
    def plan_to_joints(self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: PlanningScene,
                       options: PlannerOptions | None = None) -> PlanResult:
        opts = options or PlannerOptions()
        problem = opts.problem()
        q0, q1 = _valid_q(q_start), _valid_q(q_goal)
        if problem is not None or q0 is None or q1 is None:
            return _fail(PlanStatus.INVALID_INPUT, problem or "start and goal must be 6 finite joint angles")
        if not self.kin.within_limits(q1):
            return _fail(PlanStatus.INVALID_INPUT, "the goal configuration is outside the joint limits")
        checker = self.checker(scene, opts.margin_m)
        if not checker.is_valid(q1):
            return _fail(PlanStatus.GOAL_IN_COLLISION, f"goal collides: {checker.colliding_pairs(q1)}")
        return self._plan(q0, [q1], checker, opts)

    # --- the search ---------------------------------------------------------------------------------
    def _plan(self, q0: Vec, goals: list[Vec], checker: CollisionChecker, opts: PlannerOptions) -> PlanResult:
        if not self.kin.within_limits(q0):
            return _fail(PlanStatus.INVALID_INPUT, "the start configuration is outside the joint limits")
        if not checker.is_valid(q0):
            pairs = checker.colliding_pairs(q0)
            return _fail(PlanStatus.START_IN_COLLISION, f"start collides: {pairs or 'within the margin'}")
        t0 = time.perf_counter()
        for goal in goals:
            if checker.check_path(np.stack([q0, goal]), opts.final_resolution_rad).ok:
                path = np.stack([q0, goal])  # the straight line is free: no search needed
                return PlanResult(PlanStatus.OK, path, time.perf_counter() - t0, planner="direct",
                                  goal_q=goal.copy(), message="straight joint-space line")
        resolution = opts.edge_resolution_rad
        while True:
            result = self._search(q0, goals, checker, opts, resolution, t0)
            if result.status is not PlanStatus.NO_PATH or "re-check" not in result.message:
                return result
            if time.perf_counter() - t0 > opts.time_limit_s or resolution <= opts.final_resolution_rad:
                return result
            resolution /= 2  # the path grazed an obstacle between checked states: search more finely
            log.debug("re-check failed; searching again at %.4f rad", resolution)

    def _search(self, q0: Vec, goals: list[Vec], checker: CollisionChecker, opts: PlannerOptions,
                resolution_rad: float, t0: float) -> PlanResult:
        lower, upper = self.kin.lower_rad, self.kin.upper_rad
        if opts.joint_window_rad is not None:
            span = np.stack([q0, *goals])
            lower = np.maximum(lower, span.min(axis=0) - opts.joint_window_rad)
            upper = np.minimum(upper, span.max(axis=0) + opts.joint_window_rad)
        with _ompl_console_silenced():
            ou.RNG.setSeed(opts.seed)
            space = ob.RealVectorStateSpace(6)
            bounds = ob.RealVectorBounds(6)
            for j in range(6):
                bounds.setLow(j, float(lower[j]))
                bounds.setHigh(j, float(upper[j]))
            space.setBounds(bounds)
            ss = og.SimpleSetup(space)

            def valid(state: object) -> bool:
                return not checker.in_collision(np.array([state[i] for i in range(6)]))  # type: ignore[index]

            ss.setStateValidityChecker(valid)
            si = ss.getSpaceInformation()
            si.setStateValidityCheckingResolution(resolution_rad / space.getMaximumExtent())
            start = space.allocState()
            for j in range(6):
                start[j] = float(q0[j])
            ss.setStartState(start)
            goal_states = ob.GoalStates(si)
            for q in goals:
                g = space.allocState()
                for j in range(6):
                    g[j] = float(q[j])
                goal_states.addState(g)
            ss.setGoal(goal_states)
            planner = PLANNERS[opts.planner](si)
            if opts.range_rad is not None and hasattr(planner, "setRange"):
                planner.setRange(float(opts.range_rad))
            ss.setPlanner(planner)
            remaining = opts.time_limit_s - (time.perf_counter() - t0)
            status = ss.solve(max(remaining, 1e-3))
            kind = status.getStatus()
            if kind != ob.PlannerStatus.EXACT_SOLUTION:
                elapsed = time.perf_counter() - t0
                mapped = {
                    ob.PlannerStatus.TIMEOUT: PlanStatus.TIMEOUT,
                    ob.PlannerStatus.APPROXIMATE_SOLUTION: PlanStatus.TIMEOUT,
                    ob.PlannerStatus.INVALID_START: PlanStatus.START_IN_COLLISION,
                    ob.PlannerStatus.INVALID_GOAL: PlanStatus.GOAL_IN_COLLISION,
                }.get(kind, PlanStatus.NO_PATH)
                return _fail(mapped, f"{opts.planner}: {status.asString()} after {elapsed:.3f} s",
                             planning_time_s=elapsed, planner=opts.planner)
            ts = time.perf_counter()
            p = ss.getSolutionPath()
            if opts.simplify == "full":
                ss.simplifySolution(opts.simplify_time_s)
                p = ss.getSolutionPath()
            elif opts.simplify == "shortcut":
                simplifier = ss.getPathSimplifier()
                simplifier.reduceVertices(p)
                simplifier.ropeShortcutPath(p)
                simplifier.reduceVertices(p)
            simplify_time = time.perf_counter() - ts
            path = np.array([[p.getState(k)[j] for j in range(6)] for k in range(p.getStateCount())])
        path[0] = q0  # exact start (OMPL copies it; keep the caller's bits)
        check = checker.check_path(path, opts.final_resolution_rad)
        elapsed = time.perf_counter() - t0
        if not check.ok:
            return _fail(PlanStatus.NO_PATH,
                         f"path failed the {opts.final_resolution_rad} rad re-check at segment "
                         f"{check.first_invalid_segment}", planning_time_s=elapsed, planner=opts.planner)
        goal = min(goals, key=lambda g: float(np.linalg.norm(g - path[-1])))
        return PlanResult(PlanStatus.OK, path, elapsed, simplify_time_s=simplify_time, planner=opts.planner,
                          goal_q=goal.copy())


def _with(result: PlanResult, **changes: float) -> PlanResult:
    from dataclasses import replace

    return replace(result, **changes)  # type: ignore[arg-type]


_DEFAULT: dict[float, MotionPlanner] = {}


def default_planner(opening_m: float = MAX_OPENING_M) -> MotionPlanner:
    if opening_m not in _DEFAULT:
        _DEFAULT[opening_m] = MotionPlanner(opening_m)
    return _DEFAULT[opening_m]


def plan_to_pose(q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                 options: PlannerOptions | None = None, *, opening_m: float = MAX_OPENING_M) -> PlanResult:
    """Plan from ``q_start`` to a tcp pose in the base frame (see :meth:`MotionPlanner.plan_to_pose`)."""
    return default_planner(opening_m).plan_to_pose(q_start, T_base_tcp_goal, scene, options)


def plan_to_joints(q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: PlanningScene,
                   options: PlannerOptions | None = None, *, opening_m: float = MAX_OPENING_M) -> PlanResult:
    """Plan from ``q_start`` to the configuration ``q_goal``."""
    return default_planner(opening_m).plan_to_joints(q_start, q_goal, scene, options)
