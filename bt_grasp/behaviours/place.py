"""Place, PlaceOn and MoveTo: setting a held object down where a pose says, and moving the tool to a pose.

``Place`` reads where the held OBJECT should come to rest (its centre's x, y, its yaw, and the height of the
surface under it) and works out the tool pose from the grasp it holds (``grasp`` from PlanGrasp, ``object``
the detection that was grasped): the object's centre relative to the tool stays what it was at the grasp.
It then runs, one control period per tick:

1. carry: a planned path to a pre-place pose ``approach`` metres above the target, with the held object
   modelled as part of the robot (so it does not sweep through a neighbour);
2. descend: a straight line down until the object's bottom is ``release_gap`` above the surface, or until
   contact stops the arm early (the arm leaves its straight line, i.e. a tracking error, within
   ``contact_window`` of the target height: the object touched down);
3. open the fingers; 4. retreat straight up.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.attempts import AttemptKind, Exclusion, grasp_family
from bt_grasp.behaviours.base import HaltCancelsJob, RobotLeaf
from bt_grasp.behaviours.fixture_mask import inside_fixture
from bt_grasp.behaviours.grasp_plan import MOVED_RAD, GraspPose
from bt_grasp.behaviours.gripper import EMPTY_WIDTH_M, GRASP_FORCE_N
from bt_grasp.behaviours.motion_job import MotionJob, PathFailure, PathFn, Segment
from bt_grasp.behaviours.motion_leaves import (
    _MovingLeaf,
    cartesian_fn,
    cartesian_reason,
    detection_box,
    plan_failure,
    plan_to_pose_fn,
    retreat_after_release,
)
from bt_grasp.behaviours.objects import is_detection, object_list
from bt_grasp.behaviours.pose import Pose
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason, ReasonLike, reason_name
from bt_grasp.geometry import Mat4, inv, make_T, rot_z, signed_mm
from bt_grasp.motion.place_orientation import PlaceYaw, footprint_kind, footprint_turns_rad, place_yaws
from bt_grasp.robot_description import MAX_OPENING_M, TCP_LINK
from bt_grasp.scene.format import Scene, place_xy_problem
from bt_grasp.tree.node_api import Status, action, inout_port, input_port

if TYPE_CHECKING:
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.motion.planning_scene import Shape
    from bt_grasp.perception.results import Detection

#: the tool points down: tcp z along base -z
R_DOWN = np.diag([1.0, -1.0, -1.0])
#: how much higher the pre-place pose is put when the first one collides with something seen beside the target
HIGHER_APPROACH_M = 0.10
#: the release pose's arm configurations tried when the nearest one does not work (seeded IK: reproducible)
RELEASE_IK_SEEDS = 16
RELEASE_IK_SOLUTIONS = 8
#: how long opening the fingers may take (simulated time)
OPEN_TIMEOUT_S = 1.5
#: a held object at least this many times as tall as its footprint is wide stands and may tip (a can, a bottle)
STANDING_RATIO = 1.5
#: a standing object is let down onto the surface before the fingers open: from the release pose (``release_gap``
#: above it) the tool goes on down by the gap and this much more; contact stops the object and it slides up
#: between the pads (or the arm stalls), so it stands on the surface when the pads let go. Released 3 mm above a
#: bin's floor, a side-grasped can dropped, landed on its rim a fraction of a degree off upright with the pads'
#: sideways push, and wobbled on its rim for good (1.8-2.2 deg, never still for 1 s: PhysX keeps a tall convex
#: body rocking on its rim once set going; dropped straight from 3 mm it settles).
TOUCH_DOWN_PRESS_M = 0.002
#: then (any object) the grip is eased from the grasp's force down to this one over ``EASE_S`` of simulated time,
#: one step a tick, before the fingers open: opened from the full force, the squeezed pads spring apart one
#: after the other and push the object sideways (the can left at 70 mm/s; the hexagonal pen, pinched 14 mm
#: across, was dragged 12 mm by one pad and rolled over two of its faces, 120 deg)
EASE_FORCE_N = 4.0
EASE_S = 0.3

_HELD_PORTS = [
    input_port("grasp", object, "{grasp}", "the grasp holding the object (from PlanGrasp)"),
    input_port("held", object, "{target}", "the detection of the held object, as grasped"),
    input_port("objects", object, "{objects}", "objects seen (obstacles while carrying)"),
    input_port("approach", float, 0.10, "height of the pre-place pose above the target, m"),
    input_port("release_gap", float, 0.003, "the object's bottom above the surface at release, m"),
    input_port("contact_window", float, 0.02, "contact this close above the target = set down, m"),
    input_port("retreat", float, 0.08, "how far to back off upwards after opening, m"),
    input_port("turns", bool, True, "when the first orientation is blocked or unreachable, "
             "try the held object's footprint symmetries (half, quarter or any turn) in order"),
    input_port("free_yaw", bool, False, "the goal allows any yaw: try turns of 30 degrees too"),
    input_port("turn_deg", float, 0.0, "turn the object by this much from the pose's yaw (or "
             "from how it is held, with no yaw) before the first orientation is tried, degrees"),
    inout_port("placed", object, "objects this tree set down inside a tray or bin (the camera's object lists "
               "leave them out): obstacles here, and this place is added (not given: not kept)"),
]


#: two detections (from different frames) closer than this, centre to centre, are the same object
SAME_OBJECT_M = 0.02


def same_object(a: Detection, b: Detection) -> bool:
    """The same object seen twice (e.g. by PerceiveAll, then by Perceive): centres within 2 cm."""
    return bool(np.linalg.norm(np.subtract(a.centroid_base_m, b.centroid_base_m)) < SAME_OBJECT_M)


def table_z_base(cell: Cell, x: float, y: float) -> float:
    """The table top's height in the base frame under (x, y) (installation data)."""
    T_base_world = inv(cell.scene.T_world_base())
    return float((T_base_world @ np.array([x, y, 0.0, 1.0]))[2])


def held_offset(grasp: GraspPose, held: Detection) -> Mat4:
    """T_tcp_object: the held object's centre in the tool frame, as it was grasped."""
    T_base_obj = make_T(rot_z(float(held.yaw_rad)), list(held.centroid_base_m))
    return inv(np.asarray(grasp.T_base_tcp_grasp, dtype=float)) @ T_base_obj


def place_options(target: Pose, held: Detection, T_tcp_obj: Mat4, height_m: float, gap_m: float,
                  surface_z_m: float, turns: bool = True, free_yaw: bool = False,
                  turn_rad: float = 0.0) -> list[tuple[PlaceYaw, Mat4]]:
    """The orientations to try, in order, each with its release tool pose: the held object's centre over
    (x, y), its bottom ``gap_m`` above the surface, its yaw ``target.yaw_deg`` (no yaw: as it was held) turned
    by one of its footprint's symmetries (``bt_grasp.motion.place_orientation``; any turn with ``free_yaw``),
    smallest turn of the wrist first. Without ``turns`` only the first: of the two half-turns of a footprint
    the one nearer the grasp's tool yaw (the one orientation Place tried before it tried several)."""
    z = surface_z_m + height_m / 2 + gap_m
    held_yaw = float(held.yaw_rad)
    requested = (held_yaw if target.yaw_deg is None else math.radians(target.yaw_deg)) + turn_rad
    if turns:
        kind = footprint_kind(float(held.size_m[0]), float(held.size_m[1]), held.shape == "round")
        turns_rad = footprint_turns_rad(kind, free_yaw)
    else:
        turns_rad = (0.0, math.pi)
    yaws = place_yaws(requested, held_yaw, turns_rad)
    if not turns:
        yaws = yaws[:1]
    T_obj_tcp = inv(T_tcp_obj)
    return [(c, make_T(rot_z(c.object_yaw_rad), [target.x_m, target.y_m, z]) @ T_obj_tcp) for c in yaws]


def _wrap_half(angle: float) -> float:
    """A footprint's yaw in (-pi/2, pi/2] (a rectangle is the same half a turn on)."""
    out = (angle + math.pi / 2) % math.pi - math.pi / 2
    return out if out > -math.pi / 2 else out + math.pi


def _flag(value: object) -> bool:
    """A bool port's value (a blackboard entry may hold the text 'true' or 'false')."""
    if isinstance(value, str):
        return value.strip().lower() in ("true", "1", "yes")
    return bool(value)


def _blocked(reason: FailureReason) -> FailureReason:
    """A collision at the place is an occupied target: PLACE_BLOCKED."""
    return FailureReason.PLACE_BLOCKED if reason is FailureReason.COLLISION else reason


def _planned_or(path: NDArray[np.float64], replan: PathFn) -> PathFn:
    """The path checked when the orientation was chosen while the arm is where it starts; else ``replan``."""

    def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
        if float(np.max(np.abs(np.asarray(q, dtype=float) - path[0]))) < MOVED_RAD:
            return path
        return replan(q)

    return compute


def _raised(T: Mat4, dz: float) -> Mat4:
    out = np.array(T, dtype=float)
    out[2, 3] += dz
    return out


class _PlaceBase(HaltCancelsJob, RobotLeaf):
    """Choose the orientation, carry, descend, open, retreat. Subclasses say where the object goes
    (:meth:`target_pose`)."""

    def target_pose(self) -> tuple[Pose, Detection | None] | str:
        """(object pose in the base frame with z = surface height, the support detection or None)."""
        raise NotImplementedError

    def initialise(self) -> None:
        self.phase = "choose"
        self.job: MotionJob | None = None
        self._early: Status | None = None
        self._t_open = 0.0
        self._T_place: Mat4 | None = None
        self._rise_first = False  # the way out the last successful check found (a side grasp's)
        self._options: list[tuple[PlaceYaw, Mat4]] = []
        self._next = 0
        self._rejected: list[tuple[PlaceYaw, PathFailure, Mat4]] = []
        self._excluded: list[Exclusion] = []
        self._recorded = False
        setup = self._setup_motion()
        if isinstance(setup, Status):
            self._early = setup

    def _setup_motion(self) -> Status | None:
        """Read the ports, build the planning scenes and the ordered place orientations (tried in update)."""
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        grasp, held = self.ports.get("grasp"), self.ports.get("held")
        if not isinstance(grasp, GraspPose):
            return self.fail(FailureReason.BAD_INPUT, "no grasp on the blackboard: run PlanGrasp first")
        if not is_detection(held):
            return self.fail(FailureReason.BAD_INPUT, "'held' is not the detection of the grasped object")
        if self.cell.robot.gripper_target_width_m() > 0.0 or self.cell.robot.gripper_width_m() < EMPTY_WIDTH_M:
            return self.fail(FailureReason.NOT_HOLDING, "the gripper holds nothing to place")
        target = self.target_pose()
        if isinstance(target, str):
            return self.fail(FailureReason.BAD_INPUT, target)
        pose, support = target
        surface = pose.z_m if pose.z_m is not None else table_z_base(self.cell, pose.x_m, pose.y_m)
        T_tcp_obj = held_offset(grasp, held)
        height = float(held.size_m[2])
        gap = self.ports.require("release_gap", float)
        self._T_tcp_obj, self._gap, self._surface = T_tcp_obj, gap, surface
        options = self.orientations(pose, held, T_tcp_obj, surface)
        if isinstance(options, str):
            return self.fail(FailureReason.PLACE_BLOCKED, options)
        self._held: Detection = held
        self._grip_family = grasp_family(np.asarray(grasp.T_base_tcp_grasp, dtype=float),
                                         float(getattr(grasp, "width_m", 0.0)), held)
        options = self._screen(options)
        if not options:
            return self._all_tried_before()
        self._options = options
        self._height = height
        self._standing = height >= STANDING_RATIO * min(float(held.size_m[0]), float(held.size_m[1]))
        self._target_text = self._where(options[0][1])
        margin = 0.004
        held_shape = self.held_model(held, T_tcp_obj, margin)
        seen = object_list(self.ports.get("objects")) or ()
        remembered = [d for d in self._placed_before() if not any(same_object(d, o) for o in seen)]
        others = [d for d in (*seen, *remembered) if not same_object(d, held)]
        obstacles = tuple(detection_box(d, f"object_{i}") for i, d in enumerate(others))
        self._carry_scene = PlanningScene.from_scene(self.cell.scene, obstacles).with_attached(held_shape, TCP_LINK)
        # the descent may end touching what the object is set on (the support), nothing else
        below = tuple(o for o, d in zip(obstacles, others, strict=True)
                      if support is None or not same_object(d, support))
        self._descent_scene = PlanningScene.from_scene(self.cell.scene, below).with_attached(held_shape, TCP_LINK)
        self._retreat_scene = PlanningScene.from_scene(self.cell.scene)
        self._q_start = self.cell.robot.joint_positions()
        self.feedback_message = f"placing at {self._target_text}"
        return None

    def _screen(self, options: list[tuple[PlaceYaw, Mat4]]) -> list[tuple[PlaceYaw, Mat4]]:
        """The orientations the run's attempts leave: one that a placement of this object with this grip found
        blocked, or failed at, before is left out (kept in ``_excluded``)."""
        memory, kept = self.cell.attempts, []
        for option, T_place in options:
            what = f"turned {math.degrees(option.turn_rad):.0f} deg at {self._where(T_place)}"
            why = memory.place_exclusion(self._held, self._T_tcp_obj, T_place, what)
            if why is None:
                kept.append((option, T_place))
            else:
                self._excluded.append(why)
        return kept

    def _all_tried_before(self) -> Status:
        """Every orientation this grip allows failed before: PLACE_BLOCKED at once, nothing moved (a notice on the
        log; the grip held cannot place the object: ``GripBlocksPlace``)."""
        tried = [e for e in self._excluded if e.rule != "room"]  # a learned margin is a note, not a try
        first = tried[0] if tried else self._excluded[0]
        self._recorded = True
        self.log_attempt(self.cell.attempts.skipped(
            AttemptKind.PLACE, self.bt_path, self.tick_now(), self._held, np.eye(4), self._grip_family,
            FailureReason.PLACE_BLOCKED.value, self._excluded, grip=self._T_tcp_obj))
        return self.fail(FailureReason.PLACE_BLOCKED,
                         f"every one of {len(tried)} place orientation(s) with this grip was tried before "
                         f"and did not work; first: {first.sentence()}")

    def covers_every_turn(self) -> bool:
        """Whether the orientations tried are every one the held object's symmetry allows (turns on)."""
        return _flag(self.ports.get("turns"))

    def _record(self, reason: str | None, moved: bool) -> None:
        """The placement ended (succeeded, failed moving, or every orientation blocked): on the run's memory and
        the log, once."""
        if self._recorded:
            return
        self._recorded = True
        T_place = self._T_place if moved and self._T_place is not None else (
            self._rejected[0][2] if self._rejected else None)
        if T_place is None:
            return
        T_obj = T_place @ self._T_tcp_obj
        place_pose = (float(T_obj[0, 3]), float(T_obj[1, 3]), float(self._surface),
                      math.degrees(math.atan2(T_obj[1, 0], T_obj[0, 0])))
        self.log_attempt(self.cell.attempts.place(
            self.bt_path, self.tick_now(), self._held, self._T_tcp_obj, self._grip_family, place_pose,
            self._T_place if moved else None, [T for _, _, T in self._rejected],
            not moved and self.covers_every_turn(), reason, self._excluded, moved))

    def fail(self, reason: ReasonLike, sentence: str) -> Status:
        """FAILURE; a placement that had tried an orientation is recorded (``bt_grasp.behaviours.attempts``)."""
        if self.phase != "choose" or self._rejected:
            self._record(reason_name(reason), moved=self.phase != "choose")
        return super().fail(reason, sentence)

    def orientations(self, pose: Pose, held: Detection, T_tcp_obj: Mat4, surface_z_m: float
                     ) -> list[tuple[PlaceYaw, Mat4]] | str:
        """The place orientations to try in order, each with its release tool pose (or why there is none):
        Place's and PlaceOn's, at ``pose``, turned by the held object's footprint symmetries."""
        return place_options(pose, held, T_tcp_obj, float(held.size_m[2]), self._gap, surface_z_m,
                             turns=_flag(self.ports.get("turns")), free_yaw=_flag(self.ports.get("free_yaw")),
                             turn_rad=math.radians(self.ports.require("turn_deg", float)))

    def held_model(self, held: Detection, T_tcp_obj: Mat4, margin_m: float) -> Shape:
        """The held object as the planner carries it (tool frame): its perceived box, grown by ``margin_m``."""
        box = detection_box(held, "held", margin_m=margin_m)
        return type(box).at("held", box.size_m, T_tcp_obj)

    def _where(self, T_place: Mat4) -> str:
        """Where an option sets the object down: its centre's x;y and the surface's z (base frame)."""
        xyz = (T_place @ self._T_tcp_obj)[:3, 3]
        return f"{xyz[0]:.3f};{xyz[1]:.3f};{self._surface:.3f}"

    def _try_option(self, option: PlaceYaw, T_place: Mat4) -> tuple[NDArray[np.float64], ...] | PathFailure:
        """The carry path to the pre-place pose and the straight descent to the release pose, both checked in
        the perceived scene (the open fingers, the palm, the arm and the held object against what was seen and
        the fixtures), and the way out after the release; or why this orientation does not work.

        First as Place always planned it (the carry to the pre-place configuration nearest the arm's, then
        the straight line down from there); when that fails, from the release pose's other arm configurations
        (each: free at the release, the straight line up to the pre-place pose, the way out, then the carry to
        where the line up ends), since a wrist or elbow the other way round may clear a bin's wall."""
        turn = f"turned {math.degrees(option.turn_rad):.0f} deg"
        pre = _raised(T_place, self.ports.require("approach", float))
        planner, options = self.cell.planner, self.cell.planner_options
        failures: list[PathFailure] = []
        plan = planner.plan_to_pose(self._q_start, pre, self._carry_scene, options)
        # deferred: OMPL, pinocchio and coal come with it; a tree loads and validates without them
        from bt_grasp.motion.planner import PlanStatus

        if plan.status is PlanStatus.GOAL_IN_COLLISION:
            # something tall beside the target (a standing can in the next slot): come down from higher up
            pre = _raised(T_place, self.ports.require("approach", float) + HIGHER_APPROACH_M)
            plan = planner.plan_to_pose(self._q_start, pre, self._carry_scene, options)
        if plan.ok:
            path = np.asarray(plan.path, dtype=float)
            descent = planner.straight_line(path[-1], T_place, self._descent_scene)
            if descent.ok:
                down = np.asarray(descent.path, dtype=float)
                out = self._way_out(down[-1], T_place, turn)
                if out is None:
                    return path, down
                failures.append(out)
            else:
                sentence = f"{turn}: the descent fails ({descent.status.value}): {descent.message}"
                failures.append(PathFailure(_blocked(cartesian_reason(descent.status)), sentence))
        else:
            failure = plan_failure(plan)
            failures.append(PathFailure(_blocked(failure.reason), f"{turn}: the carry fails: {failure.sentence}"))
        releases, _ = self.cell.kinematics.ik_solutions(T_place, self._q_start, seeds=RELEASE_IK_SEEDS,
                                                        max_solutions=RELEASE_IK_SOLUTIONS)
        checker = planner.checker(self._descent_scene, 0.0)
        for q_release in releases:
            if not checker.is_valid(q_release):
                continue
            up = planner.straight_line(q_release, pre, self._descent_scene)
            if not up.ok or self._way_out(q_release, T_place, turn) is not None:
                continue
            line = np.asarray(up.path, dtype=float)
            carry = planner.plan_to_joints(self._q_start, line[-1], self._carry_scene, options)
            if carry.ok:
                return np.asarray(carry.path, dtype=float), line[::-1].copy()
        return failures[0]

    def _touched_down(self, q_release: NDArray[np.float64], T_place: Mat4) -> NDArray[np.float64]:
        """Where the arm lets go: a standing object's touch-down goes on down from the release pose (as far as
        a straight line clear of the fixtures goes; where it stops, the arm stays at the release pose)."""
        if not self._standing:
            return q_release
        line = self.cell.planner.straight_line(q_release, _raised(T_place, -self._touch_down_m()),
                                               self._retreat_scene)
        return np.asarray(line.path, dtype=float)[-1] if line.ok else q_release

    def _touch_down_m(self) -> float:
        return self._gap + TOUCH_DOWN_PRESS_M

    def _way_out(self, q_release: NDArray[np.float64], T_place: Mat4, turn: str) -> PathFailure | None:
        """Why the open gripper cannot leave the released object from ``q_release`` (None: it can); for a
        standing object, from where its touch-down ends. A side grasp backs off then rises; when that is
        blocked (the wrist, low behind a standing object, backing into a bin's wall), it rises first: the way
        that works is the one the retreat takes (``_rise_first``)."""
        q0 = self._touched_down(q_release, T_place)
        first: PathFailure | None = None
        for rise_first in (False, True):
            q, failure = q0, None
            steps = retreat_after_release(T_place, self.ports.require("retreat", float), self._height, rise_first)
            for name, fn in steps:
                line = self.cell.planner.straight_line(q, fn(self.cell.kinematics.fk(q)), self._retreat_scene)
                if not line.ok:
                    sentence = f"{turn}: the {name} after the release fails ({line.status.value}): {line.message}"
                    failure = PathFailure(_blocked(cartesian_reason(line.status)), sentence)
                    break
                q = np.asarray(line.path, dtype=float)[-1]
            if failure is None:
                self._rise_first = rise_first
                return None
            first = first or failure
            if len(steps) == 1:  # straight up: there is no other order
                break
        return first

    def _choose(self) -> Status:
        """Try the next orientation (one per tick: a plan and a straight line, tens of ms); start the motion
        with the first that works; FAILURE when none does."""
        option, T_place = self._options[self._next]
        self._next += 1
        self._target_text = self._where(T_place)
        tried = self._try_option(option, T_place)
        if isinstance(tried, PathFailure):
            self._rejected.append((option, tried, T_place))
            if self._next < len(self._options):
                self.feedback_message = f"placing at {self._target_text}: {tried.sentence}"
                return Status.RUNNING
            return self._none_works()
        carry_path, descent_path = tried
        self._T_place = T_place
        self._chosen = option
        carry = _planned_or(carry_path, self._blocked_if_collision(
            plan_to_pose_fn(self, _raised(T_place, self.ports.require("approach", float)), self._carry_scene)))
        descend = _planned_or(descent_path, self._blocked_if_collision(
            cartesian_fn(self, lambda _T: T_place, self._descent_scene)))
        segments = [Segment("carry", carry), Segment("descend", descend)]
        if self._standing:
            down = self._touch_down_m()
            segments.append(Segment("touch down", cartesian_fn(self, lambda _T: _raised(T_place, -down),
                                                               self._retreat_scene)))
        self.job = MotionJob(self.cell, segments)
        self.phase = "move"
        turned = f", turned {math.degrees(option.turn_rad):.0f} deg" if option.turn_rad else ""
        self.feedback_message = f"placing at {self._target_text}{turned}"
        return Status.RUNNING

    def _none_works(self) -> Status:
        """FAILURE: PLACE_BLOCKED when any orientation was reachable but blocked, else the first one's reason."""
        failures = [f for _, f, _ in self._rejected]
        blocked = [f for f in failures if f.reason is FailureReason.PLACE_BLOCKED]
        first = blocked[0] if blocked else failures[0]
        n = len(failures)
        what = "the one place orientation" if n == 1 else f"none of {n} place orientations works"
        return self.fail(first.reason, f"{what} at {self._target_text}: {first.sentence}")

    @staticmethod
    def _blocked_if_collision(fn: PathFn) -> PathFn:
        """A target that collides with what is seen there is an occupied target: PLACE_BLOCKED."""
        def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
            out = fn(q)
            if isinstance(out, PathFailure) and out.reason is FailureReason.COLLISION:
                return PathFailure(FailureReason.PLACE_BLOCKED, f"the place target is blocked: {out.sentence}")
            return out

        return compute

    def _tcp_z(self) -> float:
        return float(self.cell.kinematics.fk(self.cell.robot.joint_positions())[2, 3])

    def update(self) -> Status:
        if self._early is not None:
            return self._early
        if self.phase == "choose":
            return self._choose()
        assert self.job is not None and self._T_place is not None
        if self.phase == "move":
            if self.cell.robot.gripper_width_m() < EMPTY_WIDTH_M:
                self.job.cancel()
                return self.fail(FailureReason.DROPPED, f"the object left the fingers during '{self.job.current}'")
            outcome = self.job.update()
            if outcome is None:
                self.feedback_message = f"placing at {self._target_text}: {self.job.current}"
                return Status.RUNNING
            if isinstance(outcome, PathFailure):
                self.job.cancel()
                above = self._tcp_z() - float(self._T_place[2, 3])
                touched = self.job.current == "descend" and outcome.reason is FailureReason.TRACKING_ERROR
                if self.job.current == "touch down":
                    # stalled on the surface, or no straight line down from the release pose: open there
                    self.feedback_message = f"touch down ended {signed_mm(above, 'above', 'below')} the release pose"
                elif touched and above <= self.ports.require("contact_window", float):
                    self.feedback_message = f"touched down {above * 1e3:.0f} mm above the target"
                elif touched:
                    return self.fail(FailureReason.PLACE_BLOCKED,
                                       f"the descent met something {above * 100:.1f} cm above the target")
                else:
                    return self.fail(outcome.reason, outcome.sentence)
            self._t_open = self.now_s()
            self.phase = "ease"
        if self.phase == "ease":
            eased = min(1.0, (self.now_s() - self._t_open) / EASE_S)
            if eased < 1.0:
                self.cell.robot.close_gripper(force_n=GRASP_FORCE_N + (EASE_FORCE_N - GRASP_FORCE_N) * eased)
                return Status.RUNNING
            self.cell.robot.open_gripper()
            self._t_open = self.now_s()
            self.phase = "open"
            return Status.RUNNING
        if self.phase == "open":
            width = self.cell.robot.gripper_width_m()
            if width < MAX_OPENING_M - 0.002:
                if self.now_s() - self._t_open > OPEN_TIMEOUT_S:
                    return self.fail(FailureReason.TIMEOUT, f"the gripper opened only to {width * 1e3:.1f} mm")
                return Status.RUNNING
            scene = self._retreat_scene
            # straight up; after a side grasp back along the approach, then up past the object's top
            retreat = self.ports.require("retreat", float)
            steps = retreat_after_release(self._T_place, retreat, self._height, self._rise_first)
            self.job = MotionJob(self.cell, [Segment(name, cartesian_fn(self, fn, scene)) for name, fn in steps])
            self.phase = "retreat"
        outcome = self.job.update()
        if outcome is None:
            return Status.RUNNING
        if isinstance(outcome, PathFailure):
            return self.fail(outcome.reason, f"after release: {outcome.sentence}")
        self.feedback_message = f"placed at {self._target_text}"
        self._remember_place()
        self._record(None, moved=True)
        return Status.SUCCESS

    def _placed_before(self) -> tuple[Detection, ...]:
        """What the ``placed`` port holds (empty when it is not set or holds nothing yet)."""
        if not self.ports.has("placed"):
            return ()
        return object_list(self.ports.get("placed")) or ()

    def _remember_place(self) -> None:
        """Add the object just set down to ``placed`` when it went inside a tray or bin (where perception no
        longer reports it): the held detection moved to where the robot released it, turned as it was."""
        if self.ports.key("placed") is None:
            return

        held = self.ports.get("held")
        assert self._T_place is not None and is_detection(held)
        T_obj = self._T_place @ self._T_tcp_obj
        xyz = T_obj[:3, 3]
        world = np.asarray(self.cell.scene.T_world_base()) @ np.array([xyz[0], xyz[1], 0.0, 1.0])
        if inside_fixture(self.cell.scene, (float(world[0]), float(world[1]))) is None:
            return
        yaw = _wrap_half(math.atan2(T_obj[1, 0], T_obj[0, 0]))
        placed = replace(held, centroid_base_m=(float(xyz[0]), float(xyz[1]), float(xyz[2] - self._gap)),
                         yaw_rad=yaw, footprint_base_m=(), points_base_m=None)
        self.ports.set("placed", (*self._placed_before(), placed))


@action(
    ports=[
        input_port("pose", Pose, description="where the held object comes to rest: x;y[;surface_z[;yaw_deg[;frame]]] "
                   "(no z: the table; no yaw: as held)", required=True),
        *_HELD_PORTS,
    ],
    reasons=(
        FailureReason.BAD_INPUT, FailureReason.NOT_HOLDING, FailureReason.PLACE_BLOCKED, FailureReason.DROPPED,
        FailureReason.TIMEOUT, *MOTION_REASONS,
    ),
    needs_robot=True,
)
class Place(_PlaceBase):
    """Set the held object down with its centre at (x, y), on the surface at height z, turned to yaw.

    FAILURE: NOT_HOLDING (nothing in the gripper), DROPPED (it left the fingers while carried),
    PLACE_BLOCKED (the target is occupied, or the descent met something early), IK_UNREACHABLE,
    PLAN_FAILED, TRACKING_ERROR, TIMEOUT (the fingers did not open), BAD_INPUT.
    """

    def check_scene(self, scene: Scene) -> str | None:
        """A literal pose off the table or out of reach is a load error (checked before the run)."""
        if self.ports.key("pose") is not None:
            return None

        pose = self.ports.require("pose", Pose)
        T = np.asarray(scene.T_world_base()) @ np.array([pose.x_m, pose.y_m, 0.0, 1.0])
        xy = (pose.x_m, pose.y_m) if pose.frame == "world" else (float(T[0]), float(T[1]))
        problem = place_xy_problem(scene, xy)
        return f"Place pose {problem}" if problem else None

    def target_pose(self) -> tuple[Pose, Detection | None] | str:
        pose = self.ports.get("pose")
        if not isinstance(pose, Pose):
            return f"'pose' is not a pose: {pose!r}"
        return pose.in_base(self.cell.scene.T_world_base()), None


@action(
    ports=[
        input_port("object", object, "{object}", "the perceived object to place on top of"),
        input_port("align", bool, True, "turn the held object to the lower object's yaw"),
        *_HELD_PORTS,
    ],
    reasons=(
        FailureReason.BAD_INPUT, FailureReason.NOT_HOLDING, FailureReason.PLACE_BLOCKED, FailureReason.DROPPED,
        FailureReason.TIMEOUT, *MOTION_REASONS,
    ),
    needs_robot=True,
)
class PlaceOn(_PlaceBase):
    """Set the held object down centred on top of a perceived object (stacking).

    FAILURE: as Place; BAD_INPUT when ``object`` is not a perceived object.
    """

    def target_pose(self) -> tuple[Pose, Detection | None] | str:
        support = self.ports.get("object")
        if not is_detection(support):
            return "'object' is not a perceived object: run SelectObject first"
        x, y, z = (float(v) for v in support.centroid_base_m)
        yaw = math.degrees(float(support.yaw_rad)) if self.ports.get("align") else None
        return Pose(x, y, z + float(support.size_m[2]) / 2, yaw), support


@action(
    ports=[
        input_port("pose", Pose, description="tool centre point x;y[;z[;yaw_deg[;frame]]] (no z: 0.15 m above the "
                   "table; no yaw: 0)", required=True),
    ],
    reasons=(FailureReason.BAD_INPUT, *MOTION_REASONS),
    needs_robot=True,
)
class MoveTo(_MovingLeaf):
    """Plan and move the tool, pointing down, to a pose (generalises MoveAbove).
    FAILURE: IK_UNREACHABLE, PLAN_FAILED, COLLISION, TRACKING_ERROR, BAD_INPUT."""

    def segments(self) -> list[Segment] | Status:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        pose = self.ports.get("pose")
        if not isinstance(pose, Pose):
            return self.fail(FailureReason.BAD_INPUT, f"'pose' is not a pose: {pose!r}")
        base = pose.in_base(self.cell.scene.T_world_base())
        z = base.z_m if base.z_m is not None else table_z_base(self.cell, base.x_m, base.y_m) + 0.15
        T = make_T(rot_z(math.radians(base.yaw_deg or 0.0)) @ R_DOWN, [base.x_m, base.y_m, z])
        self.feedback_message = f"to {base}"
        return [Segment("move to", plan_to_pose_fn(self, T, PlanningScene.from_scene(self.cell.scene)))]
