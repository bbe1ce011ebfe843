"""PlanGrasp, Approach, Lift, Retreat, MoveHome, MoveAbove: leaves that move the arm.

The planning scene is what the robot knows: the table from the scene file's installation data and the
objects perception reported (as boxes); never the simulator's true poses.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.attempts import AttemptKind, Exclusion, GraspFamily, grasp_family
from bt_grasp.behaviours.base import HaltCancelsJob, RobotLeaf
from bt_grasp.behaviours.grasp_plan import GraspPlan
from bt_grasp.behaviours.gripper import empty_below_m, planned_width_m
from bt_grasp.behaviours.hang import HeldObject, lift_rise_m
from bt_grasp.behaviours.motion_job import MotionJob, PathFailure, PathFn, Segment
from bt_grasp.behaviours.perceive import camera_pose
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason
from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M
from bt_grasp.geometry import make_T, rot_z
from bt_grasp.perception.antipodal import AntipodalSettings, near_same, rank_grasps, sampled_grasps
from bt_grasp.perception.results import GraspCandidate
from bt_grasp.seeds import Stream
from bt_grasp.tree.node_api import Status, action, input_port, output_port

if TYPE_CHECKING:
    from bt_grasp.motion.cartesian import CartesianStatus
    from bt_grasp.motion.planner import PlanResult, PlanStatus
    from bt_grasp.motion.planning_scene import Box, PlanningScene
    from bt_grasp.perception.results import Detection

#: a tool pose computed from the current one (e.g. straight up from it)
PoseFn = Callable[[NDArray[np.float64]], NDArray[np.float64]]

def plan_reason(status: PlanStatus) -> FailureReason:
    """The leaf's failure reason for a planner status (motion is imported late: it loads pinocchio)."""
    # deferred: OMPL, pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.planner import PlanStatus

    reasons = {
        PlanStatus.IK_UNREACHABLE: FailureReason.IK_UNREACHABLE,
        PlanStatus.START_IN_COLLISION: FailureReason.COLLISION,
        PlanStatus.GOAL_IN_COLLISION: FailureReason.COLLISION,
    }
    return reasons.get(status, FailureReason.PLAN_FAILED)


def cartesian_reason(status: CartesianStatus) -> FailureReason:
    # deferred: pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.cartesian import CartesianStatus

    reasons = {
        CartesianStatus.UNREACHABLE: FailureReason.IK_UNREACHABLE,
        CartesianStatus.COLLISION: FailureReason.COLLISION,
    }
    return reasons.get(status, FailureReason.PLAN_FAILED)


def plan_failure(result: PlanResult) -> PathFailure:
    """The leaf's failure for a planner result that is not OK (the reason from the status enum)."""
    reason = plan_reason(result.status)
    return PathFailure(reason, f"planning failed ({result.status.value}): {result.message}")


def detection_box(detection: Detection, name: str, margin_m: float = 0.005) -> Box:
    # deferred: scipy comes with it; a tree loads and validates without it
    from bt_grasp.motion.planning_scene import Box

    length, width, height = detection.size_m
    T = make_T(rot_z(detection.yaw_rad), np.asarray(detection.centroid_base_m, dtype=float))
    return Box.at(name, (length + margin_m, width + margin_m, height + margin_m), T)


def planning_scene(
    leaf: RobotLeaf, target: Detection | None = None, objects: Sequence[Detection] = (), allow_target: bool = False
) -> PlanningScene:
    # deferred: scipy comes with it; a tree loads and validates without it
    from bt_grasp.motion.planning_scene import PlanningScene

    obstacles = []
    for i, det in enumerate(objects or ()):
        if target is not None and det.centroid_base_m == target.centroid_base_m:
            continue
        obstacles.append(detection_box(det, f"object_{i}"))
    scene = PlanningScene.from_scene(leaf.cell.scene, tuple(obstacles))
    if target is not None:
        box = detection_box(target, "target", margin_m=0.0)
        scene = scene.with_allowed_object(box) if allow_target else scene.with_obstacles(box)
    return scene


def plan_to_pose_fn(leaf: RobotLeaf, T_goal: NDArray[np.float64], scene: PlanningScene) -> PathFn:
    """A PathFn that plans from the measured q to a tool pose."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        result = leaf.cell.planner.plan_to_pose(q, T_goal, scene, leaf.cell.planner_options)
        return np.asarray(result.path) if result.ok else plan_failure(result)

    return compute


def plan_to_joints_fn(leaf: RobotLeaf, q_goal: NDArray[np.float64], scene: PlanningScene) -> PathFn:
    """A PathFn that plans from the measured q to a joint configuration."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        result = leaf.cell.planner.plan_to_joints(q, q_goal, scene, leaf.cell.planner_options)
        return np.asarray(result.path) if result.ok else plan_failure(result)

    return compute


def straight_up(height_m: float) -> PoseFn:
    """The goal of a vertical Cartesian segment: the current tool pose raised by height_m."""

    def up(T_now: NDArray[np.float64]) -> NDArray[np.float64]:
        T = T_now.copy()
        T[2, 3] += height_m
        return T

    return up


def back_along_approach(distance_m: float) -> PoseFn:
    """The goal of a Cartesian segment backing the tool off along its own -z (the way a grasp approached)."""

    def back(T_now: NDArray[np.float64]) -> NDArray[np.float64]:
        T = T_now.copy()
        T[:3, 3] -= distance_m * T_now[:3, 2]
        return T

    return back


def retreat_after_release(T_release: NDArray[np.float64], distance_m: float,
                          object_height_m: float, rise_first: bool = False) -> list[tuple[str, PoseFn]]:
    """How the open gripper leaves a released object, as named tool-pose steps: straight up ``distance_m`` when
    the tool points down (within 1 degree: every top-down grasp); else (a side grasp) back along the approach
    by ``distance_m``, then up by the object's height, so the arm's next motion starts above it (straight up
    at once would drag the pads along a standing object and leave them around its top). With ``rise_first``
    (where backing off low would take the wrist into a bin's wall) up by the object's height first, the open
    pads passing up beside it, then back."""
    pointing_down = float(-np.asarray(T_release, dtype=float)[2, 2]) > np.cos(np.deg2rad(1.0))
    if pointing_down:
        return [("retreat", straight_up(distance_m))]
    if rise_first:
        return [("rise", straight_up(object_height_m)), ("retreat", back_along_approach(distance_m))]
    return [("retreat", back_along_approach(distance_m)), ("rise", straight_up(object_height_m))]


def first_that_plans(*paths: PathFn) -> PathFn:
    """The first of ``paths`` that gives a joint path from the measured configuration; else the last's failure."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        outcome: NDArray[np.float64] | PathFailure = PathFailure(FailureReason.PLAN_FAILED, "no path to try")
        for path in paths:
            outcome = path(q)
            if not isinstance(outcome, PathFailure):
                return outcome
        return outcome

    return compute


def cartesian_fn(leaf: RobotLeaf, T_goal_fn: PoseFn, scene: PlanningScene) -> PathFn:
    """A straight tool line from the current pose to ``T_goal_fn(T_now)``."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        # deferred: pinocchio and coal come with it; a tree loads and validates without them
        from bt_grasp.motion.cartesian import cartesian_path

        kin = leaf.cell.kinematics
        T_now = kin.fk(q)
        result = cartesian_path(q, T_goal_fn(T_now), scene, kin=kin)
        if not result.ok:
            reason = cartesian_reason(result.status)
            return PathFailure(reason, f"straight-line segment failed ({result.status.value}): {result.message}")
        return np.asarray(result.path)

    return compute


class _MovingLeaf(HaltCancelsJob, RobotLeaf):
    """Runs a MotionJob across ticks; halting cancels the motion (the arm holds where it is)."""

    def segments(self) -> list[Segment] | Status:
        raise NotImplementedError

    def initialise(self) -> None:
        self.job: MotionJob | None = None
        self._early: Status | None = None
        segments = self.segments()
        if isinstance(segments, Status):
            self._early = segments
        else:
            self.job = MotionJob(self.cell, segments)

    def check_during(self) -> Status | None:
        return None

    def finished(self) -> Status:
        return Status.SUCCESS

    def update(self) -> Status:
        if self._early is not None:
            return self._early
        assert self.job is not None
        early = self.check_during()
        if early is not None:
            self.job.cancel()
            return early
        outcome = self.job.update()
        if outcome is None:
            self.feedback_message = f"{self.job.current}"
            return Status.RUNNING
        if isinstance(outcome, PathFailure):
            self.job.cancel()
            self.failed_in(outcome.reason, self.job.current)
            return self.fail(outcome.reason, outcome.sentence)
        return self.finished()

    def failed_in(self, reason: FailureReason, segment: str) -> None:
        """The motion failed in ``segment`` (a leaf whose motion is part of an attempt ends it here)."""


_GRASP = input_port("grasp", object, "{grasp}", "the grasp to approach (from PlanGrasp)")


#: PlanGrasp's ports (PlanRegrasp adds its own to them)
PLAN_GRASP_PORTS = (
    input_port("target", object, "{target}", "the detection to grasp"),
    input_port("objects", object, "{objects}", "every object seen (obstacles)"),
    output_port("grasp", object, "the first reachable ranked candidate, with its planned approach (a GraspPlan)",
                default="{grasp}"),
    input_port("skip", int, 0, "skip this many of the best candidates"),
    input_port("change_family_after", int, 2, "after this many failed grasps of one family (top, side, "
               "long_axis, rim) on the target, the other families' candidates go first; one grasp that stalled "
               "in contact is enough (0: never)"),
)
PLAN_GRASP_REASONS = (
    FailureReason.NO_DETECTION, FailureReason.NOTHING_TO_GRASP, FailureReason.IK_UNREACHABLE,
    FailureReason.PLAN_FAILED,
)


@action(ports=PLAN_GRASP_PORTS, reasons=PLAN_GRASP_REASONS, needs_robot=True)
class PlanGrasp(RobotLeaf):
    """Rank grasps of the target (:func:`bt_grasp.perception.antipodal.rank_grasps`: the footprint's top-down
    ones, or for a tall object side grasps sampled from its cloud first) and keep the first whose whole
    approach is collision-free.

    The run's memory of its attempts (``bt_grasp.behaviours.attempts``) screens them first: a candidate that
    repeats a failed grasp of the target (same family, within 5 mm and 10 degrees) or lies near one that stalled
    in contact (15 mm, 20 degrees) is left out, and after ``change_family_after`` failures of a family (or one
    stall) the other families go first. The grasp kept opens an attempt that Approach, Grasp and Lift end.

    One candidate per tick (IK of the pre-grasp and grasp poses, the approach plan to the pre-grasp pose, then
    the straight descent from where that plan ends to the grasp pose with the fingers open, checked against
    the perceived scene as Approach will move it: tens of ms, more than a control period), RUNNING while
    candidates remain; the kept plan (with its descent) travels with the grasp. A candidate whose descent is
    blocked is passed over here, not found blocked later in Approach.
    """

    def initialise(self) -> None:
        self._candidates: list[GraspCandidate] | None = None
        self._next = 0
        self._last = PathFailure(FailureReason.PLAN_FAILED, "no candidate")
        self._extended = False

    def update(self) -> Status:
        if self._candidates is None:
            early = self._rank()
            if early is not None:
                return early
        assert self._candidates is not None
        if self._next < len(self._candidates) or self._extend():
            rank = self._next  # counted after the skipped ones, as the feedback always did
            self._next += 1
            plan = self._try(rank, self._candidates[self._next - 1])
            if plan is not None:
                self.ports.set("grasp", plan)
                attempt = self.cell.attempts.open_grasp(self.bt_path, self.tick_now(), self._target,
                                                        plan.T_base_tcp_grasp, plan.width_m, self._excluded)
                self.feedback_message = (f"candidate {rank} of {self._total} ({attempt.family.value}"
                                         f"{self._screened_text(attempt.family)}): {plan.candidate.reason}")
                return Status.SUCCESS
            if self._next < len(self._candidates) or self._extend():
                sentence = self._last.sentence  # most already name their candidate: never "candidate 0: candidate 0:"
                named = sentence.startswith("candidate ")
                self.feedback_message = sentence if named else f"candidate {rank}: {sentence}"
                return Status.RUNNING
        if self._tried == 0 and self._excluded:
            return self._all_excluded()
        # a planner failure other than IK counts as PLAN_FAILED here, as before the typed seams
        unreachable = self._last.reason is FailureReason.IK_UNREACHABLE
        reason = FailureReason.IK_UNREACHABLE if unreachable else FailureReason.PLAN_FAILED
        self.cell.attempts.planning_failed(self._target, reason.value)
        return self.fail(reason, f"none of {self._total} grasps is reachable; last: {self._last.sentence}")

    def _rank(self) -> Status | None:
        """Synthesise and rank the candidates (first tick); a FAILURE status when there is nothing to try."""
        target = self.input_detection("target")
        if target is None:
            return self.fail(FailureReason.NO_DETECTION, "no target on the blackboard: run Perceive first")
        self._target: Detection = target
        self._objects: tuple[Detection, ...] = self.input_detections("objects")
        self._q = self.cell.robot.joint_positions()
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import fixture_boxes

        fixtures = [(box.T_base_shape, box.size_m) for box in fixture_boxes(self.cell.scene)]

        # where the camera saw the target from (eye-in-hand: the arm has not moved since Perceive)
        T_base_camera = camera_pose(self.cell)
        viewpoint = None if T_base_camera is None else tuple(float(v) for v in T_base_camera[:3, 3])
        result = rank_grasps(target, self._objects, self.cell.grasp_settings, reachable=self._reachable,
                             seed=self.cell.seeds.integer(Stream.GRASPS), fixtures=fixtures,
                             viewpoint_base_m=viewpoint)
        if not result.ok:
            self.cell.attempts.planning_failed(target, FailureReason.NOTHING_TO_GRASP.value)
            return self.fail(FailureReason.NOTHING_TO_GRASP, f"{result.status.value}: {result.message}")
        self.cell.media.grasps(result.candidates)
        self._total = len(result.candidates)
        self._ranked = result.candidates
        self._viewpoint, self._fixtures = viewpoint, fixtures
        skip = self.ports.get("skip", int) or 0
        self._skip = skip
        self._excluded: list[Exclusion] = []
        self._tried = 0
        self._families: dict[int, GraspFamily] = {}
        self._candidates = self._screen(list(result.candidates[skip:]), skip)
        if self._avoided and all(self._families[id(c)] in self._avoided for c in self._candidates):
            self._extend()  # a family to change from: the grasps sampled from the cloud may offer another first
        self._scene = planning_scene(self, target, self._objects)
        self._descent_scene = planning_scene(self, target, self._objects, allow_target=True)
        return None

    def _extend(self) -> bool:
        """Once every ranked candidate failed: add the grasps sampled from the target's cloud that are not
        near-same as one of them (:func:`~bt_grasp.perception.antipodal.sampled_grasps`; an object ranked by its
        footprint alone got none), the skip left over applied to them. Whether any was added."""
        if self._extended:
            return False
        self._extended = True

        assert self._candidates is not None
        settings = AntipodalSettings(pregrasp_offset_m=self.cell.grasp_settings.pregrasp_offset_m)
        more = sampled_grasps(self._target, self._objects, settings, reachable=self._reachable,
                              seed=self.cell.seeds.integer(Stream.GRASPS), fixtures=self._fixtures,
                              viewpoint_base_m=self._viewpoint)
        new = [c for c in more if not any(near_same(c, r) for r in self._ranked)]
        self._total += len(new)  # every candidate ranked, the skipped ones too (as the first ranking counts)
        new = new[max(0, self._skip - len(self._ranked)):]
        screened = self._screen(new, len(self._ranked) + max(0, self._skip - len(self._ranked)))
        if not screened:
            return False
        self.cell.media.grasps(tuple(screened))
        rest = self._candidates[self._next:] + screened  # the families to change from last, among all not yet tried
        self._candidates[self._next:] = ([c for c in rest if self._families[id(c)] not in self._avoided]
                                         + [c for c in rest if self._families[id(c)] in self._avoided])
        return True

    def _screen(self, candidates: Sequence[GraspCandidate], first_rank: int) -> list[GraspCandidate]:
        """The candidates the run's attempts leave (those repeating a failed grasp, or near one that stalled, are
        left out and kept in ``_excluded``), the families to change from last (stable otherwise)."""
        memory, target = self.cell.attempts, self._target
        kept: list[tuple[GraspCandidate, GraspFamily]] = []
        for i, c in enumerate(candidates):
            family = grasp_family(c.T_base_tcp_grasp, c.width_m, target)
            why = memory.grasp_exclusion(target, c.T_base_tcp_grasp, family, f"candidate {first_rank + i}")
            if why is None:
                kept.append((c, family))
                self._families[id(c)] = family
            else:
                self._excluded.append(why)
        after = self.ports.get("change_family_after", int)
        failures = memory.family_failures(target)
        self._avoided = memory.stalled_families(target) | (
            {f for f, n in failures.items() if n >= after} if after and after > 0 else set())
        first = [c for c, f in kept if f not in self._avoided]
        return first + [c for c, f in kept if f in self._avoided]

    def _screened_text(self, chosen: GraspFamily) -> str:
        parts = []
        if self._excluded:
            parts.append(f"{len(self._excluded)} left out by earlier attempts")
        if self._avoided:
            avoided = ", ".join(sorted(f.value for f in self._avoided))
            # a family to change from that is still the one chosen: no candidate of another family planned
            parts.append(f"{avoided} again: no other family left" if chosen in self._avoided
                         else f"changed from {avoided}")
        return "; " + "; ".join(parts) if parts else ""

    def _all_excluded(self) -> Status:
        """Every candidate repeats a failed attempt: nothing new to try on this object (a notice on the log)."""
        first = self._excluded[0]
        self.cell.attempts.planning_failed(self._target, FailureReason.NOTHING_TO_GRASP.value)
        T = self._ranked[0].T_base_tcp_grasp if self._ranked else np.eye(4)
        family = grasp_family(T, self._ranked[0].width_m if self._ranked else 0.0, self._target)
        self.log_attempt(self.cell.attempts.skipped(
            AttemptKind.GRASP, self.bt_path, self.tick_now(), self._target, T, family, "NOTHING_TO_GRASP",
            self._excluded))
        return self.fail(FailureReason.NOTHING_TO_GRASP,
                         f"every one of {len(self._excluded)} grasp(s) of the target repeats a failed attempt; "
                         f"first: {first.sentence()}")

    def _reachable(self, T_grasp: NDArray[np.float64], T_pregrasp: NDArray[np.float64]) -> bool:
        """Both poses have an IK solution from the arm's configuration (how sampled candidates are kept)."""
        kin = self.cell.kinematics
        pre = kin.ik(T_pregrasp, self._q)
        return bool(pre.ok and kin.ik(T_grasp, pre.q).ok)

    def _try(self, rank: int, candidate: GraspCandidate) -> GraspPlan | None:
        self._tried += 1
        kin, q = self.cell.kinematics, self._q
        pre = kin.ik(candidate.T_base_tcp_pregrasp, q)
        if not pre.ok:
            self._last = PathFailure(FailureReason.IK_UNREACHABLE, f"candidate {rank}: pre-grasp unreachable")
            return None
        at = kin.ik(candidate.T_base_tcp_grasp, pre.q)
        if not at.ok:
            self._last = PathFailure(FailureReason.IK_UNREACHABLE, f"candidate {rank}: grasp pose unreachable")
            return None
        options = self.cell.planner_options
        plan = self.cell.planner.plan_to_pose(q, candidate.T_base_tcp_pregrasp, self._scene, options)
        if not plan.ok:
            sentence = f"candidate {rank}: {plan.status.value} ({plan.message})"
            self._last = PathFailure(plan_reason(plan.status), sentence)
            return None
        path = np.asarray(plan.path, dtype=float)
        descent = self.cell.planner.straight_line(path[-1], candidate.T_base_tcp_grasp, self._descent_scene)
        if not descent.ok:
            sentence = f"candidate {rank}: the straight descent fails ({descent.status.value}): {descent.message}"
            self._last = PathFailure(cartesian_reason(descent.status), sentence)
            return None
        return GraspPlan(candidate, q.copy(), path, self._target, self._objects,
                         descent_path=np.asarray(descent.path, dtype=float))


@action(
    ports=[
        _GRASP,
        input_port("target", object, "{target}", "the detection being grasped"),
        input_port("objects", object, "{objects}", "every object seen (obstacles)"),
    ],
    reasons=(FailureReason.BAD_INPUT, *MOTION_REASONS),
    needs_robot=True,
)
class Approach(_MovingLeaf):
    """Move to the pre-grasp pose along the path PlanGrasp planned (planned anew if the arm moved or the scene
    changed since), then move in a straight line along the grasp's approach axis to the grasp pose (down for
    a top-down grasp, sideways for a side grasp; the pre-grasp lies back along -approach)."""

    def segments(self) -> list[Segment] | Status:
        grasp = self.ports.get("grasp")
        if not isinstance(grasp, GraspPlan | GraspCandidate):
            return self.fail(FailureReason.BAD_INPUT, "no grasp on the blackboard: run PlanGrasp first")
        target, objects = self.input_detection("target"), self.input_detections("objects")
        free = planning_scene(self, target, objects)
        touching = planning_scene(self, target, objects, allow_target=True)
        T_grasp = grasp.T_base_tcp_grasp
        to_pregrasp = plan_to_pose_fn(self, grasp.T_base_tcp_pregrasp, free)
        descend = cartesian_fn(self, lambda _T: T_grasp, touching)
        if isinstance(grasp, GraspPlan) and grasp.planned_in(target, objects):
            to_pregrasp = planned_path_fn(grasp, to_pregrasp)
        # the straight line runs along the grasp's approach axis (tcp z): down for a top-down grasp
        down = float(-np.asarray(T_grasp, dtype=float)[2, 2]) > 0.866
        return [
            Segment("to pre-grasp", to_pregrasp),
            Segment("descend" if down else "approach", descend),
        ]

    def initialise(self) -> None:
        super().initialise()
        if self.job is not None:
            self.cell.attempts.moving()  # the grasp PlanGrasp chose is being made

    def failed_in(self, reason: FailureReason, segment: str) -> None:
        # a stall on the straight way into the object is a stall in contact: its neighbourhood is ruled out
        self.end_attempt(reason.value, in_contact=segment in ("descend", "approach"))


def planned_path_fn(plan: GraspPlan, replan: PathFn) -> PathFn:
    """The plan's approach path while the arm is where the plan starts; else ``replan`` (the arm moved)."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        return plan.approach_path if plan.starts_at(q) else replan(q)

    return compute


@action(
    ports=[
        input_port("height", float, DEFAULT_LIFT_HEIGHT_M, "how far to lift, m: the tool, or with target the object's "
                   "centre"),
        input_port("grasp", object, "{grasp}", "the grasp holding the object (from PlanGrasp): its width seen says "
                   "what an empty grip is"),
        input_port("target", object, "", "the object held, as perceived (from Perceive): when given, its centre rises "
                   "height, the tool further by how far the object can hang below the grip (bt_grasp.behaviours.hang)"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.SLIPPED, *MOTION_REASONS),
    needs_robot=True,
)
class Lift(_MovingLeaf):
    """Lift straight up; FAILURE (SLIPPED) when the fingers lose the object on the way: their gap falls under
    :func:`~bt_grasp.behaviours.gripper.empty_below_m` of the grasp's width seen (a thin plate is held at
    ~4 mm), as Grasp judges it.

    Without ``target`` the tool rises ``height``. With it (and a grasp on the blackboard) the object is what
    rises ``height``: the tool rises further by how far the object's perceived centre may sink by turning about
    where the pads hold it (:func:`~bt_grasp.behaviours.hang.lift_rise_m`: 0 for a grasp through the centre or
    above it, about the lever's length for a centre level with the grip, as a bowl held by its rim; for a rim
    grasp, the lever to the farthest held point seen, as the object may slide in the pads). When that
    higher line is out of reach or blocked, the tool rises ``height`` alone."""

    def segments(self) -> list[Segment] | Status:
        grasp = self.ports.get("grasp")
        self._empty_below = empty_below_m(planned_width_m(grasp))
        height = self.ports.require("height", float)
        if not 0.0 < height < 0.6:
            return self.fail(FailureReason.BAD_INPUT, f"lift height {height} m is outside (0, 0.6)")
        target = self.input_detection("target")
        T_grasp = getattr(grasp, "T_base_tcp_grasp", None)
        held = None if target is None else HeldObject(
            target.centroid_base_m, target.size_m, target.yaw_rad,
            None if target.points_base_m is None else np.asarray(target.points_base_m, dtype=float),
            planned_width_m(grasp) or 0.0)
        T = None if T_grasp is None else np.asarray(T_grasp, dtype=float)
        by_wall = (target is not None and T is not None
                   and grasp_family(T, planned_width_m(grasp) or 0.0, target) is GraspFamily.RIM)
        rise = lift_rise_m(height, T, held, by_wall)
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        scene = PlanningScene.from_scene(self.cell.scene)
        if rise <= height:
            self.feedback_message = f"lifting {height * 100:.0f} cm"
            return [Segment("lift", cartesian_fn(self, straight_up(height), scene))]
        self.cell.media.log("INFO", self.name,
                            f"lifting the object {height * 100:.1f} cm: the tool {rise * 100:.1f} cm (held off its "
                            f"centre, it may hang up to {(rise - height) * 100:.1f} cm lower from the grip)")
        return [Segment("lift", first_that_plans(cartesian_fn(self, straight_up(rise), scene),
                                                 cartesian_fn(self, straight_up(height), scene)))]

    def check_during(self) -> Status | None:
        width = self.cell.robot.gripper_width_m()
        if width < self._empty_below:
            self.end_attempt(FailureReason.SLIPPED.value)
            return self.fail(FailureReason.SLIPPED, f"the object slipped out: fingers at {width * 1e3:.1f} mm")
        return None

    def failed_in(self, reason: FailureReason, segment: str) -> None:
        self.end_attempt(reason.value)

    def finished(self) -> Status:
        width = self.cell.robot.gripper_width_m()
        if width < self._empty_below:
            self.end_attempt(FailureReason.SLIPPED.value)
            return self.fail(FailureReason.SLIPPED, f"the object slipped out: fingers at {width * 1e3:.1f} mm")
        self.feedback_message = f"lifted, holding {width * 1e3:.1f} mm"
        self.end_attempt(None)
        return Status.SUCCESS


@action(
    ports=[
        input_port("height", float, 0.10, "how far to back off upwards, m"),
    ],
    reasons=MOTION_REASONS,
    needs_robot=True,
)
class Retreat(_MovingLeaf):
    """Back off straight up from wherever the tool is."""

    def segments(self) -> list[Segment] | Status:
        height = self.ports.require("height", float)
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        return [Segment("retreat", cartesian_fn(self, straight_up(height), PlanningScene.from_scene(self.cell.scene)))]


@action(reasons=MOTION_REASONS, needs_robot=True)
class MoveHome(_MovingLeaf):
    """Plan and move to the scene's home configuration."""

    def segments(self) -> list[Segment] | Status:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        home = np.asarray(self.cell.scene.robot.home_q_rad, dtype=float)
        return [Segment("home", plan_to_joints_fn(self, home, PlanningScene.from_scene(self.cell.scene)))]


@action(
    ports=[
        input_port("x", float, description="tool x in the base frame, m", required=True),
        input_port("y", float, description="tool y in the base frame, m", required=True),
        input_port("height", float, 0.15, "tool height above the table, m"),
    ],
    reasons=MOTION_REASONS,
    needs_robot=True,
)
class MoveAbove(_MovingLeaf):
    """Plan and move the tool, pointing down, above a point of the table (e.g. to set an object aside)."""

    def segments(self) -> list[Segment] | Status:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        T = np.eye(4)
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])
        T[:3, 3] = [self.ports.require("x", float), self.ports.require("y", float), self.ports.require("height", float)]
        T = np.linalg.inv(self.cell.scene.T_world_base()) @ T
        return [Segment("move above", plan_to_pose_fn(self, T, PlanningScene.from_scene(self.cell.scene)))]
