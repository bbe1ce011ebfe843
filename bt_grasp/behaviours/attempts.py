"""A run's memory of what it tried (issue 46): every grasp and placement attempt, how it ended, and which later
attempts it rules out.

The robot leaves share one :class:`AttemptMemory` through the cell (``cell.attempts``), one per run:

- ``PlanGrasp`` opens a grasp attempt with the candidate it chose (the object as perceived, the tool pose, its
  :class:`GraspFamily`); ``Approach``, ``Grasp`` and ``Lift`` end it (``Lift``'s success: SUCCEEDED; a failure:
  the leaf's reason). ``Place``, ``PlaceOn``, ``PlaceIn`` and ``SetDown`` record a placement attempt: where the
  object was to rest, the release tool pose, the grip (the object in the tool frame) and every orientation
  they found blocked.
- Grasp planning, placement and object selection consult it: a candidate that repeats a failed attempt is
  left out (:meth:`AttemptMemory.grasp_exclusion`, :meth:`AttemptMemory.place_exclusion`), one near a grasp
  that stalled in contact too, a family that failed ``change_family_after`` times on an object goes last
  (:meth:`AttemptMemory.family_failures`), an object that failed goes last (:meth:`AttemptMemory.object_failures`).

**The same attempt, in numbers** (:class:`AttemptRules`, the tree may change them with ``AttemptRules``): two
attempts are the same when they are on the same object, of the same family, and their tool poses lie within
``same_m`` (5 mm) and ``same_deg`` (10 degrees) of each other. A parallel gripper turned half a turn about its
approach axis holds the same way, so a pose and its twin (closing direction reversed) are one pose: the angle is
the smaller of the two. A placement also needs the same grip (the object in the tool frame within the same
bounds). A grasp that stalled in contact (``TRACKING_ERROR``) rules out every grasp of the object within
``stall_m`` (15 mm) and ``stall_deg`` (20 degrees) of it, whatever its family; one that failed for reach or
collision (``IK_UNREACHABLE``, ``COLLISION``, ``PLAN_FAILED``, ``PLACE_BLOCKED``) rules out that pose and its
twin, as any other failure does.

Each attempt ends on the log's ``/bt/attempts`` channel (what, where, how it ended, what it ruled out:
:meth:`Attempt.to_json`), which ``replay --attempts`` and the run report show. Nothing here reads ground truth:
objects are what perception reported, poses what the planner chose.
"""

from __future__ import annotations

import enum
import math
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.geometry import Mat4, inv, make_T, rot_z

if TYPE_CHECKING:
    from bt_grasp.perception.results import Detection


@dataclass(frozen=True)
class AttemptRules:
    """When one attempt repeats another, and how far a stall reaches (lengths in metres, angles in degrees)."""

    same_m: float = 0.005  # tool poses this close (and within same_deg) are the same attempt
    same_deg: float = 10.0
    stall_m: float = 0.015  # a grasp that stalled in contact rules out grasps this close (and within stall_deg)
    stall_deg: float = 20.0

    def __post_init__(self) -> None:
        for name in ("same_m", "same_deg", "stall_m", "stall_deg"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"attempt rule {name} must be a finite number >= 0, got {value}")


class AttemptKind(enum.StrEnum):
    GRASP = "grasp"
    PLACE = "place"


class GraspFamily(enum.StrEnum):
    """How a grasp holds its object (from the tool pose, the width between the pads and the object as seen)."""

    TOP = "top"  # from above, across the whole object
    SIDE = "side"  # from the side (or obliquely), across the whole object
    LONG_AXIS = "long_axis"  # from above, across an elongated object's long axis (a pen, a banana, a lying bottle)
    RIM = "rim"  # the pads close on a wall or rim, much thinner than the object there (a mug's or a bowl's)


class Outcome(enum.StrEnum):
    SUCCEEDED = "SUCCEEDED"
    FAILED = "FAILED"  # the fingers closed on nothing, it slipped or dropped, a timeout
    STALLED = "STALLED"  # the arm stopped against something it touched (TRACKING_ERROR)
    BLOCKED = "BLOCKED"  # unreachable or in collision (IK, plan, collision, every place orientation blocked)
    UNFINISHED = "UNFINISHED"  # the run ended with the attempt still going (written at the end)
    SKIPPED = "SKIPPED"  # not made: every option it had repeats a failed attempt (a notice, not an attempt)


#: the reasons that mean "not reachable or in collision" (the pose and its twin are ruled out)
BLOCKED_REASONS = frozenset({"IK_UNREACHABLE", "COLLISION", "PLAN_FAILED", "PLACE_BLOCKED"})
#: the reason that means "stalled in contact" (its neighbourhood is ruled out)
STALL_REASONS = frozenset({"TRACKING_ERROR"})

#: a grasp is a rim grasp when the pads close on less than this fraction of the object's extent there ...
RIM_FRACTION = 0.5
#: ... and at least this much less than it, m
RIM_MARGIN_M = 0.015
#: an object this many times longer than wide is elongated (as perception's shape classes say)
ELONGATED_RATIO = 2.5
#: a tool within this of pointing straight down grasps from above, degrees
TOP_DOWN_DEG = 30.0
#: two detections are the same object when their centres lie this close, m ...
SAME_OBJECT_M = 0.03
#: ... and their footprints' long sides differ by at most this fraction
SAME_SIZE_FRACTION = 0.3
#: an object of the kind and size a failed grasp was on, this close to where it was, is that object, pushed, m
FOLLOW_M = 0.05


def outcome_of(reason: str | None) -> Outcome:
    """An ended attempt's outcome from the reason its leaf failed with (None: it succeeded)."""
    if reason is None:
        return Outcome.SUCCEEDED
    if reason in STALL_REASONS:
        return Outcome.STALLED
    if reason in BLOCKED_REASONS:
        return Outcome.BLOCKED
    return Outcome.FAILED


def _half_turn_z() -> Mat4:
    T = np.eye(4)
    T[0, 0] = T[1, 1] = -1.0
    return T


_TWIN = _half_turn_z()


def pose_gap(T_a: Mat4, T_b: Mat4) -> tuple[float, float]:
    """(distance m, angle deg) between two tool poses, a pose and its twin (the gripper half a turn about its
    approach axis: the same grip with the closing direction reversed) being one pose."""
    Ta, Tb = np.asarray(T_a, dtype=float), np.asarray(T_b, dtype=float)
    distance = float(np.linalg.norm(Ta[:3, 3] - Tb[:3, 3]))
    angles = []
    for Tb_twin in (Tb, Tb @ _TWIN):
        c = (float(np.trace(Ta[:3, :3].T @ Tb_twin[:3, :3])) - 1.0) / 2.0
        angles.append(math.degrees(math.acos(max(-1.0, min(1.0, c)))))
    return distance, min(angles)


def within(T_a: Mat4, T_b: Mat4, distance_m: float, angle_deg: float) -> bool:
    d, a = pose_gap(T_a, T_b)
    return d <= distance_m and a <= angle_deg


@dataclass(frozen=True)
class ObjectSeen:
    """What an attempt was made on, as perceived (base frame): enough to tell it again in a later frame."""

    centroid_m: tuple[float, float, float]
    size_m: tuple[float, float, float]
    yaw_deg: float
    label: str = ""
    class_name: str = ""
    shape_class: str = ""
    color_name: str = ""

    @classmethod
    def of(cls, det: Detection) -> ObjectSeen:
        shape_class = getattr(det, "shape_class", "")
        c, s = det.centroid_base_m, det.size_m
        return cls((float(c[0]), float(c[1]), float(c[2])), (float(s[0]), float(s[1]), float(s[2])),
                   math.degrees(float(det.yaw_rad)), str(det.label), str(getattr(det, "class_name", "") or ""),
                   str(getattr(shape_class, "value", shape_class) or ""), str(getattr(det, "color_name", "") or ""))

    def same_as(self, other: ObjectSeen) -> bool:
        """The same object: centres within :data:`SAME_OBJECT_M`, footprints of a like size, and the same class
        when both were named."""
        if math.dist(self.centroid_m, other.centroid_m) > SAME_OBJECT_M:
            return False
        a, b = max(self.size_m[:2]), max(other.size_m[:2])
        if abs(a - b) > SAME_SIZE_FRACTION * max(a, b, 1e-6):
            return False
        return not (self.class_name and other.class_name and self.class_name != other.class_name)

    def like(self, other: ObjectSeen) -> bool:
        """Of one kind and size (wherever each was seen): footprints of a like size, the same class when both
        were named."""
        return ObjectSeen(other.centroid_m, self.size_m, self.yaw_deg, class_name=self.class_name).same_as(other)

    def describe(self) -> str:
        name = self.class_name or self.label or "object"
        x, y, _ = self.centroid_m
        return f"{name} at ({x:.3f}, {y:.3f})"

    def to_json(self) -> JsonObject:
        return {"centroid_m": [round(v, 4) for v in self.centroid_m], "size_m": [round(v, 4) for v in self.size_m],
                "yaw_deg": round(self.yaw_deg, 1), "label": self.label, "class_name": self.class_name,
                "shape_class": self.shape_class, "color_name": self.color_name}


def extent_along(det: Detection | ObjectSeen, direction: Sequence[float] | NDArray[np.float64]) -> float:
    """How far the object's perceived box reaches along a unit direction (base frame), m."""
    size = det.size_m
    yaw = math.radians(det.yaw_deg) if isinstance(det, ObjectSeen) else float(det.yaw_rad)
    u = (math.cos(yaw), math.sin(yaw))
    d = [float(v) for v in direction]
    return (float(size[0]) * abs(d[0] * u[0] + d[1] * u[1]) + float(size[1]) * abs(-d[0] * u[1] + d[1] * u[0])
            + float(size[2]) * abs(d[2]))


def grasp_family(T_base_tcp: Mat4, width_m: float, target: Detection | ObjectSeen) -> GraspFamily:
    """The family of a grasp (tcp z = approach, tcp y = closing) on an object as perceived."""
    T = np.asarray(T_base_tcp, dtype=float)
    extent = extent_along(target, T[:3, 1])
    if width_m < RIM_FRACTION * extent and extent - width_m > RIM_MARGIN_M:
        return GraspFamily.RIM
    if -float(T[2, 2]) < math.cos(math.radians(TOP_DOWN_DEG)):
        return GraspFamily.SIDE
    length, width = float(max(target.size_m[:2])), float(min(target.size_m[:2]))
    if length >= ELONGATED_RATIO * max(width, 1e-6):
        return GraspFamily.LONG_AXIS
    return GraspFamily.TOP


@dataclass(frozen=True)
class Exclusion:
    """Why an option (a grasp candidate, a place orientation, an object) was left out: the attempt that rules it
    out and the rule."""

    what: str  # "candidate 3", "turned 90 deg", "can at (0.41, 0.05)"
    by: int  # the index of the attempt that rules it out (-1: a rule of the tree, not an attempt)
    rule: str  # "repeat", "stall", "family", "object"
    detail: str

    def to_json(self) -> JsonObject:
        return {"what": self.what, "by": self.by, "rule": self.rule, "detail": self.detail}

    def sentence(self) -> str:
        by = f" (attempt #{self.by})" if self.by >= 0 else ""
        return f"{self.what}: {self.detail}{by}"


def _T_json(T: Mat4 | None) -> JsonValue:
    if T is None:
        return None
    return [round(float(v), 5) for v in np.asarray(T, dtype=float).reshape(-1)]


@dataclass(frozen=True)
class Attempt:
    """One grasp or placement attempt and how it ended.

    ``T_base_tcp``: the grasp pose (grasp), or the release tool pose of the orientation tried (place).
    ``T_tcp_object``: a placement's grip (the held object in the tool frame). ``blocked``: a placement's release
    poses found blocked before the arm moved (every one, when ``every_turn_blocked``). ``place_pose``: where the
    object was to rest (x, y, surface z in m, yaw in degrees; base frame)."""

    index: int
    kind: AttemptKind
    leaf: str
    tick: int
    object: ObjectSeen
    T_base_tcp: Mat4
    family: GraspFamily
    approach: str  # how the tool comes in ("top-down", "side from (+0.71, -0.71, 0.00)", "carry from above")
    outcome: Outcome = Outcome.UNFINISHED
    reason: str | None = None
    end_tick: int | None = None
    end_leaf: str = ""
    width_m: float = 0.0
    T_tcp_object: Mat4 | None = None
    place_pose: tuple[float, float, float, float] | None = None
    blocked: tuple[Mat4, ...] = ()
    every_turn_blocked: bool = False
    excluded: tuple[Exclusion, ...] = ()
    #: moved the arm (a placement found blocked before the arm moved did not; it is still an attempt)
    moved: bool = False

    @property
    def failed(self) -> bool:
        return self.outcome not in (Outcome.SUCCEEDED, Outcome.UNFINISHED, Outcome.SKIPPED)

    @property
    def grip_failed(self) -> bool:
        """A placement that says its grip will not do: the object left the fingers (DROPPED), or no orientation
        was left to try with it (every one blocked, or a notice that each repeated a failed one). A later grasp
        of the object with that grip repeats it."""
        if self.kind is not AttemptKind.PLACE:
            return False
        return self.reason == "DROPPED" or (self.reason == "PLACE_BLOCKED"
                                            and (self.every_turn_blocked or self.outcome is Outcome.SKIPPED))

    def failed_poses(self) -> tuple[Mat4, ...]:
        """The tool poses this attempt found not to work: every orientation found blocked before the arm moved,
        and the one it moved to when it failed there."""
        moved_to = (self.T_base_tcp,) if self.moved and self.failed else ()
        return self.blocked + moved_to

    def describe(self) -> str:
        what = f"{self.kind.value} #{self.index} on {self.object.describe()}"
        how = f"{self.family.value}" + (f", at {_place_text(self.place_pose)}" if self.place_pose else "")
        end = self.outcome.value + (f" {self.reason}" if self.reason else "")
        return f"{what} ({how}): {end}"

    def to_json(self) -> JsonObject:
        """The ``/bt/attempts`` message."""
        T = np.asarray(self.T_base_tcp, dtype=float)
        out: JsonObject = {
            "index": self.index, "kind": self.kind.value, "leaf": self.leaf, "tick": self.tick,
            "end_tick": self.end_tick if self.end_tick is not None else self.tick, "end_leaf": self.end_leaf,
            "outcome": self.outcome.value, "reason": self.reason or "", "object": self.object.to_json(),
            "family": self.family.value, "approach": self.approach,
            "tcp_xyz_m": [round(float(v), 4) for v in T[:3, 3]],
            "approach_dir": [round(float(v), 3) for v in T[:3, 2]],
            "closing_dir": [round(float(v), 3) for v in T[:3, 1]],
            "T_base_tcp": _T_json(T), "width_m": round(self.width_m, 4), "moved": self.moved,
            "excluded": [e.to_json() for e in self.excluded],
        }
        if self.kind is AttemptKind.PLACE:
            out["place_pose"] = [round(v, 4) for v in self.place_pose] if self.place_pose else []
            if self.T_tcp_object is not None:
                out["T_tcp_object"] = _T_json(self.T_tcp_object)
            out["blocked"] = [{"T_base_tcp": _T_json(b)} for b in self.blocked]
            out["every_turn_blocked"] = self.every_turn_blocked
        return out


def _place_text(pose: tuple[float, float, float, float] | None) -> str:
    if pose is None:
        return "-"
    x, y, z, yaw = pose
    return f"{x:.3f};{y:.3f};{z:.3f};{yaw:.0f}"


@dataclass
class AttemptMemory:
    """The attempts of one run, in order, with the one still going (``current``)."""

    rules: AttemptRules = field(default_factory=AttemptRules)
    attempts: list[Attempt] = field(default_factory=list)
    current: Attempt | None = None
    #: the last placement found no orientation it may try with the grip held (blocked now or before)
    grip_blocked: bool = False
    #: objects grasp planning gave up on (no candidate, none reachable): not attempts, but failures on the object
    unplanned: list[tuple[ObjectSeen, str]] = field(default_factory=list)
    #: objects followed from where they were seen to where they are seen now (pairs (was, now)): a failed grasp
    #: that pushed its object a few cm, one found again by FindLost, one set down by SetDown. What was tried on
    #: it before still counts after it moved.
    moves: list[tuple[ObjectSeen, ObjectSeen]] = field(default_factory=list)

    # -- recording ---------------------------------------------------------------------------------------

    def open_grasp(self, leaf: str, tick: int, target: Detection, T_base_tcp: Mat4, width_m: float,
                   excluded: Sequence[Exclusion] = ()) -> Attempt:
        """PlanGrasp chose a grasp: it is the attempt now going (an earlier one that never moved the arm is
        dropped: it was planned, not made)."""
        if self.current is not None and not self.current.moved:
            self.current = None
        self._follow_after_failure(target)
        T = np.asarray(T_base_tcp, dtype=float)
        family = grasp_family(T, width_m, target)
        a = -T[:3, 2]
        approach = ("top-down" if family in (GraspFamily.TOP, GraspFamily.LONG_AXIS) or a[2] >= 0.866
                    else f"from ({-a[0]:+.2f}, {-a[1]:+.2f}, {-a[2]:+.2f})")
        attempt = Attempt(self._next_index(), AttemptKind.GRASP, leaf, tick, ObjectSeen.of(target), T, family,
                          approach, width_m=float(width_m), excluded=tuple(excluded))
        self.current = attempt
        return attempt

    def moving(self) -> None:
        """The arm started moving for the attempt going (Approach began)."""
        if self.current is not None and not self.current.moved:
            self.current = replace(self.current, moved=True)

    def end(self, reason: str | None, leaf: str, tick: int, in_contact: bool = False) -> Attempt | None:
        """End the attempt going (a grasp): SUCCEEDED with ``reason`` None, else by the reason; a stall counts as
        STALLED only ``in_contact`` (the tool's straight way into the object), else as FAILED. Returns it, to be
        written to the log (None when none was going, or it never moved the arm)."""
        attempt = self.current
        if attempt is None or not attempt.moved:
            return None
        self.current = None
        outcome = outcome_of(reason)
        if outcome is Outcome.STALLED and not in_contact:
            outcome = Outcome.FAILED
        done = replace(attempt, outcome=outcome, reason=reason, end_tick=tick, end_leaf=leaf)
        self.attempts.append(done)
        return done

    def place(self, leaf: str, tick: int, held: Detection, grip: Mat4, family: GraspFamily,
              place_pose: tuple[float, float, float, float], T_release: Mat4 | None,
              blocked: Sequence[Mat4], every_turn_blocked: bool, reason: str | None,
              excluded: Sequence[Exclusion] = (), moved: bool = True) -> Attempt:
        """A placement ended (succeeded, failed while moving, or every orientation it tried was blocked)."""
        T = np.asarray(T_release if T_release is not None else (blocked[0] if blocked else np.eye(4)), dtype=float)
        attempt = Attempt(self._next_index(), AttemptKind.PLACE, leaf, tick, ObjectSeen.of(held), T, family,
                          "carry from above", outcome_of(reason), reason, tick, leaf,
                          T_tcp_object=np.asarray(grip, dtype=float), place_pose=place_pose,
                          blocked=tuple(np.asarray(b, dtype=float) for b in blocked),
                          every_turn_blocked=every_turn_blocked, excluded=tuple(excluded), moved=moved)
        self.attempts.append(attempt)
        self.grip_blocked = every_turn_blocked and not moved and reason is not None
        return attempt

    def skipped(self, kind: AttemptKind, leaf: str, tick: int, obj: Detection, T_base_tcp: Mat4,
                family: GraspFamily, reason: str, excluded: Sequence[Exclusion], grip: Mat4 | None = None
                ) -> Attempt:
        """A leaf had nothing left to try (every option repeats a failed attempt): a notice for the log, not an
        attempt made. A placement's notice means the grip held cannot place the object (``grip_blocked``)."""
        attempt = Attempt(self._next_index(), kind, leaf, tick, ObjectSeen.of(obj), np.asarray(T_base_tcp, float),
                          family, "-", Outcome.SKIPPED, reason, tick, leaf, excluded=tuple(excluded),
                          T_tcp_object=None if grip is None else np.asarray(grip, dtype=float))
        self.attempts.append(attempt)
        if kind is AttemptKind.PLACE:
            self.grip_blocked = True
        return attempt

    def finish(self, tick: int) -> Attempt | None:
        """The run ended: the attempt still going, if it moved the arm, as UNFINISHED (to be written)."""
        attempt = self.current
        self.current = None
        if attempt is None or not attempt.moved:
            return None
        done = replace(attempt, end_tick=tick)
        self.attempts.append(done)
        return done

    def moved(self, was: ObjectSeen, now: Detection | ObjectSeen) -> None:
        """The object seen as ``was`` is the one seen as ``now`` (it moved): its attempts go with it."""
        self.moves.append((was, now if isinstance(now, ObjectSeen) else ObjectSeen.of(now)))

    def _follow_after_failure(self, target: Detection) -> None:
        """A grasp right after a failed one, on an object of its kind and size within :data:`FOLLOW_M` of it that
        is not another object the run tried, is on that object, pushed by the failed grasp (an L bracket slid
        2.5 cm at each of five slips, and each attempt counted as the first on a new object)."""
        last = self.attempts[-1] if self.attempts else None
        if last is None or last.kind is not AttemptKind.GRASP or not last.failed:
            return
        seen = ObjectSeen.of(target)
        if math.dist(last.object.centroid_m, seen.centroid_m) > FOLLOW_M or not last.object.like(seen):
            return
        # an object the run tried before, other than the pushed one, is itself
        pushed = self._identities(last.object)
        if any(a.object.same_as(seen) and not any(a.object.same_as(i) for i in pushed) for a in self.attempts):
            return
        self.moved(last.object, seen)

    def _identities(self, seen: ObjectSeen) -> list[ObjectSeen]:
        """Every way the object was seen (where it was before it moved, where it went), ``seen`` first."""
        out = [seen]
        grew = True
        while grew:
            grew = False
            for was, now in self.moves:
                known_was, known_now = (any(x.same_as(o) for o in out) for x in (was, now))
                if known_was != known_now:
                    out.append(now if known_was else was)
                    grew = True
        return out

    def _next_index(self) -> int:
        return len(self.attempts) + (1 if self.current is not None else 0)

    # -- consulting --------------------------------------------------------------------------------------

    def on(self, target: Detection | ObjectSeen, kind: AttemptKind | None = None) -> list[Attempt]:
        """The ended attempts on this object (of one kind)."""
        seen = target if isinstance(target, ObjectSeen) else ObjectSeen.of(target)
        ids = self._identities(seen)
        return [a for a in self.attempts
                if (kind is None or a.kind is kind) and any(a.object.same_as(i) for i in ids)]

    def grasp_exclusion(self, target: Detection, T_base_tcp: Mat4, family: GraspFamily, what: str
                        ) -> Exclusion | None:
        """Why a grasp candidate may not be tried (None: it may): it repeats a failed grasp (same family,
        within ``same_m``/``same_deg``), lies near one that stalled (``stall_m``/``stall_deg``, any family), or
        repeats a grip a placement dropped."""
        r = self.rules
        for a in self.on(target):
            grip = a.T_base_tcp if a.kind is AttemptKind.GRASP else None
            if a.kind is AttemptKind.PLACE:
                if not a.grip_failed or a.T_tcp_object is None:
                    continue
                grip = _grasp_of_place(a, target)
            if grip is None or (not a.failed and a.kind is AttemptKind.GRASP):
                continue
            d, ang = pose_gap(grip, T_base_tcp)
            if a.outcome is Outcome.STALLED and d <= r.stall_m and ang <= r.stall_deg:
                return Exclusion(what, a.index, "stall", f"{d * 1e3:.0f} mm and {ang:.0f} deg from a grasp that "
                                 f"stalled in contact (within {r.stall_m * 1e3:.0f} mm and {r.stall_deg:.0f} deg)")
            if a.family is family and d <= r.same_m and ang <= r.same_deg:
                return Exclusion(what, a.index, "repeat", f"repeats a {family.value} grasp that ended "
                                 f"{a.reason or a.outcome.value} ({d * 1e3:.0f} mm, {ang:.0f} deg from it)")
        return None

    def family_failures(self, target: Detection) -> Counter[GraspFamily]:
        """Failed grasps per family on this object."""
        out: Counter[GraspFamily] = Counter()
        for a in self.on(target, AttemptKind.GRASP):
            if a.failed:
                out[a.family] += 1
        return out

    def stalled_families(self, target: Detection) -> set[GraspFamily]:
        return {a.family for a in self.on(target, AttemptKind.GRASP) if a.outcome is Outcome.STALLED}

    def planning_failed(self, target: Detection, reason: str) -> None:
        """Grasp planning found nothing to try on this object (it counts among the object's failures)."""
        self.unplanned.append((ObjectSeen.of(target), reason))

    def object_failures(self, target: Detection) -> int:
        """Failures on this object: failed attempts (grasps and placements) and grasp plannings that gave up."""
        seen = ObjectSeen.of(target)
        ids = self._identities(seen)
        return (sum(1 for a in self.on(seen) if a.failed)
                + sum(1 for o, _ in self.unplanned if any(o.same_as(i) for i in ids)))

    def place_exclusion(self, held: Detection, grip: Mat4, T_release: Mat4, what: str) -> Exclusion | None:
        """Why a release pose may not be tried with this grip (None: it may): a placement of this object with
        the same grip found it blocked, or failed there, before."""
        r = self.rules
        for a in self.on(held, AttemptKind.PLACE):
            if a.T_tcp_object is None or not within(a.T_tcp_object, grip, r.same_m, r.same_deg):
                continue
            for T in a.failed_poses():
                d, ang = pose_gap(T, T_release)
                if d <= r.same_m and ang <= r.same_deg:
                    return Exclusion(what, a.index, "repeat", f"with this grip the same release ({d * 1e3:.0f} mm, "
                                     f"{ang:.0f} deg) ended {a.reason or a.outcome.value} before")
        return None

    def early_contacts(self, held: Detection, grip: Mat4) -> list[Attempt]:
        """Placements of this object with this grip whose descent met something before the target (PLACE_BLOCKED
        after the arm moved): each says the held object reaches further than its perceived shape in the fingers
        (it hangs off-centre, or turned in the grip), so the next spot wants more room round it."""
        r = self.rules
        return [a for a in self.on(held, AttemptKind.PLACE)
                if a.moved and a.reason == "PLACE_BLOCKED" and a.T_tcp_object is not None
                and within(a.T_tcp_object, grip, r.same_m, r.same_deg)]

    def last_lost(self) -> Attempt | None:
        """The last failed grasp (the object it was on may have moved: a search looks for it)."""
        for a in reversed(self.attempts):
            if a.kind is AttemptKind.GRASP:
                return a if a.failed else None
        return None


def _grasp_of_place(place: Attempt, target: Detection) -> Mat4 | None:
    """The grasp a placement's grip stands for, on the object where it is now seen (its centre and yaw)."""
    if place.T_tcp_object is None:
        return None
    T_obj = make_T(rot_z(float(target.yaw_rad)), list(target.centroid_base_m))
    return np.asarray(T_obj @ inv(np.asarray(place.T_tcp_object, dtype=float)), dtype=float)


def repeats(attempts: Iterable[JsonObject], rules: AttemptRules | None = None) -> list[tuple[int, int]]:
    """Pairs (earlier, later) of logged attempts (``/bt/attempts`` messages) where the later one repeats a failed
    earlier one by the rules: the same kind, object, family (and grip, for a placement), tool poses within
    ``same_m``/``same_deg`` (a grasp within ``stall_m``/``stall_deg`` of one that stalled). What the issue's
    "never the same failing attempt twice" is counted by."""
    r = rules or AttemptRules()
    done: list[JsonObject] = []
    out: list[tuple[int, int]] = []
    for msg in attempts:
        for earlier in done:
            if _repeats(earlier, msg, r):
                out.append((int(_num(earlier.get("index"))), int(_num(msg.get("index")))))
                break
        done.append(msg)
    return out


def _num(value: JsonValue) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else 0.0


def _matrix(value: JsonValue) -> Mat4 | None:
    if not isinstance(value, list) or len(value) != 16:
        return None
    return np.array([_num(v) for v in value], dtype=float).reshape(4, 4)


def _seen(value: JsonValue) -> ObjectSeen | None:
    if not isinstance(value, dict):
        return None
    c, s = value.get("centroid_m"), value.get("size_m")
    if not (isinstance(c, list) and isinstance(s, list) and len(c) == 3 and len(s) == 3):
        return None
    return ObjectSeen((_num(c[0]), _num(c[1]), _num(c[2])), (_num(s[0]), _num(s[1]), _num(s[2])),
                      _num(value.get("yaw_deg")), str(value.get("label", "")), str(value.get("class_name", "")))


def _repeats(earlier: JsonObject, later: JsonObject, r: AttemptRules) -> bool:
    if earlier.get("kind") != later.get("kind") or earlier.get("outcome") in ("UNFINISHED", "SKIPPED"):
        return False
    if earlier.get("outcome") == "SUCCEEDED" and (earlier.get("kind") != AttemptKind.PLACE.value
                                                  or not _blocked(earlier)):
        return False  # (a placement that worked may still have found orientations blocked first)
    if later.get("outcome") == Outcome.SKIPPED.value:  # a notice that nothing was tried
        return False
    a, b = _seen(earlier.get("object")), _seen(later.get("object"))
    if a is None or b is None or not a.same_as(b):
        return False
    later_T, earlier_T = _matrix(later.get("T_base_tcp")), _matrix(earlier.get("T_base_tcp"))
    if later_T is None or earlier_T is None:
        return False
    later_poses, earlier_poses = [later_T], [earlier_T]
    if later.get("kind") == AttemptKind.PLACE.value:
        ga, gb = _matrix(earlier.get("T_tcp_object")), _matrix(later.get("T_tcp_object"))
        if ga is None or gb is None or not within(ga, gb, r.same_m, r.same_deg):
            return False
        # what each tried: the orientations found blocked, and the one it moved to (failed, for the earlier)
        later_poses = _blocked(later) + ([later_T] if later.get("moved") else [])
        failed_there = earlier.get("moved") and earlier.get("outcome") != Outcome.SUCCEEDED.value
        earlier_poses = _blocked(earlier) + ([earlier_T] if failed_there else [])
    stalled = earlier.get("outcome") == Outcome.STALLED.value and earlier.get("kind") == AttemptKind.GRASP.value
    same_family = earlier.get("family") == later.get("family")
    for Te in earlier_poses:
        for Tl in later_poses:
            d, ang = pose_gap(Te, Tl)
            if stalled and d <= r.stall_m and ang <= r.stall_deg:
                return True
            if same_family and d <= r.same_m and ang <= r.same_deg:
                return True
    return False


def _blocked(msg: JsonObject) -> list[Mat4]:
    value = msg.get("blocked")
    items = value if isinstance(value, list) else []
    poses = (_matrix(item.get("T_base_tcp")) if isinstance(item, dict) else None for item in items)
    return [T for T in poses if T is not None]
