"""Joint-space motion planning with OMPL 2 (nanobind bindings) in a planning scene.

``plan_to_joints`` plans from a start configuration to a goal configuration; ``plan_to_pose`` first
solves IK for a tool pose (every closed-form solution of the UR arm is collision-checked and the free ones
closest to the start become the goal states, so the planner picks whichever it reaches) and then plans.
Both return a :class:`PlanResult` whose status says what went wrong; no bad request raises.

Collision checking along edges: OMPL's motion validator checks states at most
``edge_resolution_rad`` apart (L2 in joint space, hence also on every joint); the simplified path is then
re-checked at ``final_resolution_rad`` (max joint step, 0.01 rad by default) before it is returned.

Determinism (same request, same seed, same result on any machine at any load): no decision reads the
clock. The search ends on a work budget (``max_state_checks`` validity checks, through an OMPL termination
condition, ``budget.py``), simplification makes fixed passes (or spends its own check budget), IK is
closed-form (or, for an arm without one, a fixed number of iterations per seed from a fixed seed list),
and the re-search at a finer resolution happens at most ``max_refinements`` times.
``ompl.util.RNG.setSeed(seed)`` reseeds OMPL's seed generator before every search and every OMPL object
that draws numbers is created after it (OMPL logs "Random number generation already started" on
reseeding; it reseeds all the same). The one clock read is the safety net
(``safety_limit_s``), which fails the request as ``SAFETY_TIMEOUT`` and logs a warning.
"""

from __future__ import annotations

import enum
import logging
import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from bt_grasp.geometry import Mat4
from bt_grasp.motion.budget import WorkBudget
from bt_grasp.motion.cartesian import CartesianResult, cartesian_path
from bt_grasp.motion.collision import FINE_RESOLUTION_RAD, CollisionChecker, collision_checker
from bt_grasp.motion.kinematics import default_kinematics, is_rigid_transform
from bt_grasp.motion.planning_scene import PlanningScene
from bt_grasp.robot_description import MAX_OPENING_M

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]

#: single-threaded OMPL planners only: PRM and PRMstar grow their roadmap in a second thread, so the states they
#: check depend on thread scheduling (and a Python termination condition deadlocks with that thread)
PLANNERS: dict[str, Callable[[ob.SpaceInformation], ob.Planner]] = {
    "RRTConnect": og.RRTConnect,
    "RRT": og.RRT,
    "RRTstar": og.RRTstar,
    "InformedRRTstar": og.InformedRRTstar,
    "SORRTstar": og.SORRTstar,
    "BITstar": og.BITstar,
    "AORRTC": og.AORRTC,
}


class PlanStatus(enum.Enum):
    OK = "ok"
    IK_UNREACHABLE = "ik_unreachable"  # no IK solution for the goal pose (proven beyond reach, or none found
    #                                    from the whole IK seed budget)
    START_IN_COLLISION = "start_in_collision"  # or within the margin of the scene
    GOAL_IN_COLLISION = "goal_in_collision"  # every IK solution of the seed budget (or the goal q) collides
    NO_PATH = "no_path"  # the planner proved nothing and ended without a path, or the path failed the re-check
    INVALID_INPUT = "invalid_input"  # NaN, wrong shape, out of limits, bad options, unknown planner
    BUDGET_EXHAUSTED = "budget_exhausted"  # the search spent its whole work budget without an exact path
    SAFETY_TIMEOUT = "safety_timeout"  # the wall-clock safety net fired (never the normal end of a search)
    TIMEOUT = "timeout"  # kept for compatibility (fault plans name it); the planner itself never returns it


@dataclass(frozen=True)
class PlannerOptions:
    """How to plan. Every limit that decides an outcome counts work, never time (see ``budget.py``).

    The defaults were chosen on ``bt-grasp bench plan`` (docs/motion.md, "Budgets").
    """

    planner: str = "RRTConnect"  # a key of PLANNERS
    max_state_checks: int = 40_000  # the search's work budget: state validity checks (incl. along edges)
    seed: int = 1  # OMPL's RNG seed and the IK seeds' generator (OMPL treats 0 as "random": avoid it)
    simplify: str = "shortcut"  # "none" | "shortcut" (fixed passes) | "full" (OMPL's simplify, on a budget)
    simplify_state_checks: int = 4_000  # the work budget of "full" simplification
    edge_resolution_rad: float = 0.025  # collision checks along edges during the search
    final_resolution_rad: float = FINE_RESOLUTION_RAD  # re-check of the returned path
    max_refinements: int = 2  # searches again at half the edge resolution when the re-check fails
    margin_m: float = 0.01  # minimum clearance to scene shapes (not applied to self-collision)
    range_rad: float | None = 1.0  # the tree planners' step size; None lets OMPL choose (~6 rad here)
    joint_window_rad: float | None = math.pi  # search only within this of the start/goal span per joint
    ik_seeds: int = 40  # the IK seed budget of plan_to_pose (q_start first, then seeded random starts)
    max_goal_configs: int = 3  # stop seeding IK once this many distinct collision-free solutions exist
    safety_limit_s: float = 30.0  # wall-clock safety net per request: SAFETY_TIMEOUT, logged; never a budget

    def problem(self) -> str | None:
        """Why these options are unusable, or None."""
        if self.planner not in PLANNERS:
            return f"unknown planner '{self.planner}'; known: {', '.join(PLANNERS)}"
        for name in ("safety_limit_s", "edge_resolution_rad", "final_resolution_rad"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                return f"{name} must be a positive number, got {value}"
        for name in ("max_state_checks", "simplify_state_checks", "ik_seeds", "max_goal_configs"):
            if int(getattr(self, name)) < 1:
                return f"{name} must be >= 1, got {getattr(self, name)}"
        if self.max_refinements < 0:
            return f"max_refinements must be >= 0, got {self.max_refinements}"
        if not (math.isfinite(self.margin_m) and self.margin_m >= 0):
            return f"margin_m must be >= 0, got {self.margin_m}"
        if self.simplify not in ("none", "shortcut", "full"):
            return f"simplify must be 'none', 'shortcut' or 'full', got '{self.simplify}'"
        if self.seed < 1:
            return "seed must be >= 1 (OMPL reads 0 as 'seed from the clock')"
        return None


@dataclass(frozen=True)
class PlanResult:
    """A planned joint path (N, 6) from the start to a goal configuration, or why there is none.

    The ``*_time_s`` fields are wall-clock measurements for benchmarks and logs only; no decision reads
    them and no message quotes them (messages are part of a run's recorded, reproducible output).
    """

    status: PlanStatus
    path: Vec = field(default_factory=lambda: np.zeros((0, 6)))
    planning_time_s: float = 0.0  # search + simplification + fine re-check
    ik_time_s: float = 0.0
    simplify_time_s: float = 0.0
    planner: str = ""
    message: str = ""
    goal_q: Vec | None = None
    state_checks: int = 0  # validity checks the search spent (its budget's unit)
    goal_configs: int = 0  # collision-free IK goals handed to the search (plan_to_pose)

    @property
    def ok(self) -> bool:
        return self.status is PlanStatus.OK

    @property
    def path_length_rad(self) -> float:
        """Euclidean joint-space length of the path."""
        if len(self.path) < 2:
            return 0.0
        return float(np.sum(np.linalg.norm(np.diff(self.path, axis=0), axis=1)))


def _fail(status: PlanStatus, message: str, **kw: float | str | int) -> PlanResult:
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


@dataclass(frozen=True)
class GoalSet:
    """The collision-free IK goals of a pose, closest to the start first, and what seeding found."""

    goals: list[Vec]
    solutions: int  # distinct IK solutions found (free or not)
    seeds_used: int  # 0: closed-form IK (every solution)
    first_colliding: Vec | None = None
    best_error: tuple[float, float] = (float("inf"), float("inf"))  # m, rad (when none converged)


class MotionPlanner:
    """Plans arm motions for a gripper opening (the collision model's fingers sit at that opening)."""

    def __init__(self, opening_m: float = MAX_OPENING_M, urdf_path: Path | None = None) -> None:
        """``urdf_path``: the robot with another gripper (``bt_grasp.cell.grippers``); None: bt_grasp's own."""
        self.opening_m = float(opening_m)
        self.kin = default_kinematics(self.opening_m, urdf_path)
        self.urdf_path = urdf_path

    def checker(self, scene: PlanningScene, margin_m: float) -> CollisionChecker:
        return collision_checker(scene, float(margin_m), self.opening_m, self.urdf_path)

    def straight_line(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene
                      ) -> CartesianResult:
        """A straight tool line from ``fk(q_start)`` (``bt_grasp.motion.cartesian.cartesian_path``)."""
        return cartesian_path(q_start, T_base_tcp_goal, scene, kin=self.kin)

    # --- pose goals ---------------------------------------------------------------------------------
    def goal_set(self, q0: Vec, T_base_tcp_goal: Mat4, checker: CollisionChecker, opts: PlannerOptions) -> GoalSet:
        """The collision-free IK goals of a pose: up to ``max_goal_configs``, closest to ``q0`` first.

        With the arm's closed-form IK (a UR arm: ``analytic_ik.py``), *every* solution of the pose is
        collision-checked, so no free goal is missed and "in collision" means all of them collide. Without it,
        seeded IK runs until ``max_goal_configs`` distinct free solutions exist or ``ik_seeds`` are spent:
        ``q0`` first, then uniform draws from a generator seeded with ``opts.seed`` (the same request always
        tries the same seeds); every solution is checked as it is found.
        """
        closed = self.kin.closed_form_ik(T_base_tcp_goal, q0)
        if closed is not None:  # closest first: each solution checked once, until enough are free
            free: list[Vec] = []
            colliding: Vec | None = None
            for q in closed:
                if checker.is_valid(q):
                    free.append(q)
                    if len(free) == opts.max_goal_configs:
                        break
                elif colliding is None:
                    colliding = q
            return GoalSet(free, len(closed), 0, None if free else colliding,
                           (0.0, 0.0) if closed else (float("inf"),) * 2)
        rng = np.random.default_rng(opts.seed)
        tried: list = []  # type: ignore[type-arg]
        free = []
        found = 0
        first_colliding: Vec | None = None
        for q in self.kin.iter_ik_solutions(T_base_tcp_goal, q0, seeds=opts.ik_seeds, rng=rng, tried=tried):
            found += 1
            if checker.is_valid(q):
                free.append(q)
                if len(free) >= opts.max_goal_configs:
                    break
            elif first_colliding is None:
                first_colliding = q
        free.sort(key=lambda g: float(np.linalg.norm(g - q0)))
        best = min(tried, key=lambda t: t.position_error_m + t.rotation_error_rad, default=None)
        error = (best.position_error_m, best.rotation_error_rad) if best is not None else (float("inf"),) * 2
        return GoalSet(free, found, len(tried), first_colliding, error)

    def plan_to_pose(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                     options: PlannerOptions | None = None) -> PlanResult:
        """IK for the tcp pose (a set of collision-free solutions), then a joint-space plan to any of them."""
        opts = options or PlannerOptions()
        problem = opts.problem()
        q0 = _valid_q(q_start)
        if problem is not None or q0 is None:
            return _fail(PlanStatus.INVALID_INPUT, problem or f"bad start configuration {q_start!r}")
        if not is_rigid_transform(T_base_tcp_goal):
            return _fail(PlanStatus.INVALID_INPUT, "the goal pose is not a finite rigid transform")
        beyond_m = self.kin.beyond_reach_m(T_base_tcp_goal)
        if beyond_m > 0:
            return _fail(PlanStatus.IK_UNREACHABLE, f"the goal lies {beyond_m * 1e3:.0f} mm beyond the arm's reach")
        t0 = time.perf_counter()
        checker = self.checker(scene, opts.margin_m)
        found = self.goal_set(q0, T_base_tcp_goal, checker, opts)
        ik_time = time.perf_counter() - t0
        source = f"from {found.seeds_used} seeds" if found.seeds_used else "(closed form: every solution)"
        if found.solutions == 0:
            pe, re = found.best_error
            error = f" (best error {pe * 1e3:.1f} mm, {np.rad2deg(re):.2f} deg)" if found.seeds_used else ""
            return _fail(PlanStatus.IK_UNREACHABLE, f"no IK solution {source}{error}", ik_time_s=ik_time)
        if not found.goals:
            q_bad = found.first_colliding
            pairs = checker.colliding_pairs(q_bad) if q_bad is not None else []
            return _fail(PlanStatus.GOAL_IN_COLLISION,
                         f"all {found.solutions} IK solutions {source} collide "
                         f"(first: {pairs or 'within margin'})", ik_time_s=ik_time)
        result = self._plan(q0, found.goals, checker, opts)
        return replace(result, ik_time_s=ik_time, goal_configs=len(found.goals))

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
        return replace(self._plan(q0, [q1], checker, opts), goal_configs=1)

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
        budget = WorkBudget.start(opts.max_state_checks, opts.safety_limit_s)
        resolution = opts.edge_resolution_rad
        for refinement in range(opts.max_refinements + 1):
            result = self._search(q0, goals, checker, opts, resolution, budget.sub(opts.max_state_checks))
            result = replace(result, planning_time_s=time.perf_counter() - t0)
            if result.status is not PlanStatus.NO_PATH or "re-check" not in result.message:
                return result
            if refinement == opts.max_refinements or resolution <= opts.final_resolution_rad:
                return result
            resolution /= 2  # the path grazed an obstacle between checked states: search more finely
            log.debug("re-check failed; searching again at %.4f rad", resolution)
        raise AssertionError("unreachable")  # pragma: no cover

    def _search(self, q0: Vec, goals: list[Vec], checker: CollisionChecker, opts: PlannerOptions,
                resolution_rad: float, budget: WorkBudget) -> PlanResult:
        lower, upper = self.kin.lower_rad, self.kin.upper_rad
        if opts.joint_window_rad is not None:
            span = np.stack([q0, *goals])
            lower = np.maximum(lower, span.min(axis=0) - opts.joint_window_rad)
            upper = np.minimum(upper, span.max(axis=0) + opts.joint_window_rad)
        with _ompl_console_silenced():
            ou.RNG.setSeed(opts.seed)  # every OMPL object below draws from streams seeded from here
            space = ob.RealVectorStateSpace(6)
            bounds = ob.RealVectorBounds(6)
            for j in range(6):
                bounds.setLow(j, float(lower[j]))
                bounds.setHigh(j, float(upper[j]))
            space.setBounds(bounds)
            ss = og.SimpleSetup(space)
            ss.setStateValidityChecker(budget.wrap(lambda q: not checker.in_collision(q)))
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
            status = ss.solve(budget.ptc())
            kind = status.getStatus()
            checks = budget.spent
            if budget.safety_hit:
                return _fail(PlanStatus.SAFETY_TIMEOUT,
                             f"{opts.planner}: the {opts.safety_limit_s:g} s wall-clock safety net stopped the "
                             f"search", planner=opts.planner, state_checks=checks)
            if kind != ob.PlannerStatus.EXACT_SOLUTION:
                mapped = {
                    ob.PlannerStatus.TIMEOUT: PlanStatus.BUDGET_EXHAUSTED,
                    ob.PlannerStatus.APPROXIMATE_SOLUTION: PlanStatus.BUDGET_EXHAUSTED,
                    ob.PlannerStatus.INVALID_START: PlanStatus.START_IN_COLLISION,
                    ob.PlannerStatus.INVALID_GOAL: PlanStatus.GOAL_IN_COLLISION,
                }.get(kind, PlanStatus.NO_PATH)
                return _fail(mapped, f"{opts.planner}: {status.asString()} after {checks} of "
                             f"{opts.max_state_checks} state checks", planner=opts.planner, state_checks=checks)
            ts = time.perf_counter()
            p = ss.getSolutionPath()
            simplifier = ss.getPathSimplifier()
            if opts.simplify == "full":
                simplify_budget = budget.sub(opts.simplify_state_checks)
                ss.setStateValidityChecker(simplify_budget.wrap(lambda q: not checker.in_collision(q)))
                simplifier.simplify(p, simplify_budget.ptc())
                if simplify_budget.safety_hit:
                    return _fail(PlanStatus.SAFETY_TIMEOUT, f"the {opts.safety_limit_s:g} s wall-clock safety "
                                 "net stopped the simplification", planner=opts.planner, state_checks=checks)
            elif opts.simplify == "shortcut":  # fixed passes: their work depends on the path, not the clock
                simplifier.reduceVertices(p)
                simplifier.ropeShortcutPath(p)
                simplifier.reduceVertices(p)
            simplify_time = time.perf_counter() - ts
            path = np.array([[p.getState(k)[j] for j in range(6)] for k in range(p.getStateCount())])
        path[0] = q0  # exact start (OMPL copies it; keep the caller's bits)
        check = checker.check_path(path, opts.final_resolution_rad)
        if not check.ok:
            return _fail(PlanStatus.NO_PATH,
                         f"path failed the {opts.final_resolution_rad} rad re-check at segment "
                         f"{check.first_invalid_segment}", planner=opts.planner, state_checks=checks)
        goal = min(goals, key=lambda g: float(np.linalg.norm(g - path[-1])))
        return PlanResult(PlanStatus.OK, path, simplify_time_s=simplify_time, planner=opts.planner,
                          goal_q=goal.copy(), state_checks=checks)


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
