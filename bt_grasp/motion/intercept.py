"""Intercepting an object on a running belt: where and when the tool meets it, and the motion that gets it there.

The object's motion model (``bt_grasp.perception.belt_track``) says where its centroid will be at any time; the
grasp (a tool pose relative to that centroid: objects ride the belt without turning) says where the tool must be
then. The intercept is the moment ``t_arrive`` at which the tool is ``hover_m`` above that grasp pose moving with
the belt; from there the tool rides with the object (the *match*): it descends to the grasp in ``descend_s``
(a quintic: no speed across the belt at either end, so at contact the tool moves exactly as the belt does), closes
the fingers, rises by the lift height while it slows from the belt's speed to rest. Everything the match needs must
lie in the arm's reach along the belt (:func:`reach_window`), so the planner chooses the earliest ``t_arrive``
that (1) a jerk-limited joint trajectory from the arm's current state reaches with the belt's velocity at the end
(ruckig: a target velocity, a duration at least ``slack`` times its shortest), (2) keeps the tool above the
arrival height on the way (the objects on the belt stay clear), and (3) leaves the whole match inside the window.
No such time is a missed intercept (the leaf's ``INTERCEPT_MISSED``).

Plain arithmetic on the kinematic model and ruckig: no simulator, no truth.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import ruckig
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, make_T, rot_z
from bt_grasp.motion.kinematics import KinematicModel

Vec = NDArray[np.float64]

#: the tool pointing down (tcp z = base -z), its x axis along base x, before its yaw
TOOL_DOWN = np.diag([1.0, -1.0, -1.0])
#: two neighbouring samples of the reach window's arm configurations differ by less than this (no branch flip), rad
_BRANCH_JUMP_RAD = 0.8
#: the reach window is sampled this finely along the belt, m (a few IK queries per sample)
_WINDOW_STEP_M = 0.03
#: finite difference for the joint velocity that moves the tool with the belt, s
_FD_S = 0.01


#: a belt faster than this is a fast one: the ride is shortened (:meth:`InterceptSettings.for_belt`), m/s
FAST_BELT_M_S = 0.35


@dataclass(frozen=True)
class InterceptSettings:
    """How the tool meets and rides with the object (times in s, lengths in m, joint limits per joint)."""

    hover_m: float = 0.08  # tcp above its grasp pose when it arrives, moving with the belt
    descend_s: float = 0.40  # from hover to grasp, riding with the belt
    close_s: float = 0.40  # the longest the fingers are given to close, riding with the belt
    lift_s: float = 0.60  # rising by the lift height
    slow_after_s: float = 0.15  # into the lift (the object ~1 cm off the belt) the tool starts to slow ...
    slow_s: float = 0.40  # ... from the belt's speed to rest, over this long
    max_velocity_rad_s: float = 2.5  # a UR5's joints: 3.14 rad/s
    max_acceleration_rad_s2: float = 10.0
    max_jerk_rad_s3: float = 150.0
    slack: float = 1.15  # the approach takes at least this times its shortest duration
    earliest_s: float = 0.15  # no intercept sooner than this from now
    horizon_s: float = 6.0  # nor later than this
    step_s: float = 0.02  # arrival times tried
    margin_m: float = 0.03  # the match stays this far inside the reach window
    clearance_m: float = 0.015  # the approach's tcp never goes lower than the arrival height minus this
    max_reach_m: float = 0.78  # the ride stays this close to the robot's base axis horizontally (a stretched arm's
    # joints move fast for a little tool motion: at 0.84 m the descent's IK jumped)

    @classmethod
    def for_belt(cls, speed_m_s: float, hover_m: float = 0.08, descend_s: float = 0.0) -> InterceptSettings:
        """The settings for a belt running at ``speed_m_s``: on a fast one (above :data:`FAST_BELT_M_S`) the
        descent and the time given to close are 0.25 s, not 0.4 s (at 50 cm/s the ride of 1.15 s took 58 cm of the
        arm's 1.17 m of belt, and the approach had none left); ``descend_s`` > 0 sets the descent anyway."""
        fast = abs(speed_m_s) > FAST_BELT_M_S
        return cls(hover_m=hover_m, descend_s=descend_s if descend_s > 0 else (0.25 if fast else 0.40),
                   close_s=0.25 if fast else 0.40)

    def match_travel_s(self) -> float:
        """How long the tool moves at the belt's speed during the match, at most (its slowing counts half)."""
        return self.descend_s + self.close_s + self.slow_after_s + self.slow_s / 2


def tool_down(position: Vec, yaw_rad: float) -> Mat4:
    """A tool pose pointing down at ``position``, its x axis at ``yaw_rad`` about base z."""
    return make_T(rot_z(yaw_rad) @ TOOL_DOWN, position)


def quintic(u: float) -> float:
    """0 -> 1 with zero slope and curvature at both ends (u clipped to [0, 1])."""
    u = min(max(u, 0.0), 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u * u)


def slowing(tau_s: float, slow_s: float) -> float:
    """Distance (in units of the belt's speed times s) a tool slowing from belt speed to rest over ``slow_s`` covers
    ``tau_s`` into the slowing: speed (1 + cos(pi tau / slow)) / 2."""
    t = min(max(tau_s, 0.0), slow_s)
    return 0.5 * t + slow_s / (2 * math.pi) * math.sin(math.pi * t / slow_s)


@dataclass(frozen=True)
class BeltGrasp:
    """A grasp of an object on the belt: the tool's pose relative to the object's centroid (a translation
    ``offset_m``, base frame, and the tool's orientation ``R_base_tcp``: the object does not turn) and the
    object's width between the pads."""

    offset_m: Vec
    R_base_tcp: NDArray[np.float64]
    width_m: float

    @classmethod
    def from_pose(cls, T_base_tcp: Mat4, centroid_m: Vec, width_m: float) -> BeltGrasp:
        T = np.asarray(T_base_tcp, dtype=float)
        return cls(T[:3, 3] - np.asarray(centroid_m, dtype=float), T[:3, :3].copy(), float(width_m))

    def T_at(self, centroid_m: Vec, rise_m: float = 0.0) -> Mat4:
        """The grasp pose for the object at ``centroid_m``, raised ``rise_m``."""
        p = np.asarray(centroid_m, dtype=float) + self.offset_m + np.array([0.0, 0.0, rise_m])
        return make_T(self.R_base_tcp, p)


@dataclass(frozen=True)
class ReachWindow:
    """Where along the belt (metres from its upstream end) the tool reaches the grasp and its hover pose with one
    arm configuration family: ``lo`` to ``hi``; ``q`` are the configurations at ``along`` (hover height)."""

    lo: float
    hi: float
    along: Vec
    q: NDArray[np.float64]

    def seed_at(self, along_m: float) -> Vec:
        """The window's configuration nearest ``along_m`` (a seed that keeps IK on the window's branch)."""
        k = int(np.clip(np.searchsorted(self.along, along_m), 0, len(self.along) - 1))
        return np.asarray(self.q[k], dtype=float)

    @property
    def empty(self) -> bool:
        return self.hi <= self.lo


def nearest_ik(kin: KinematicModel, T: Mat4, q_ref: Vec, *, near_rad: float = 0.5) -> Vec | None:
    """The IK solution of ``T`` nearest ``q_ref``, or None: the numerical solver from ``q_ref`` (~1 ms) when it
    lands within ``near_rad`` of it on every joint, else the closed form's nearest solution (~5 ms, every branch)."""
    result = kin.ik(T, q_ref, seeds=1)
    if result.ok and float(np.max(np.abs(np.asarray(result.q) - q_ref))) <= near_rad:
        return np.asarray(result.q, dtype=float)
    closed = getattr(kin, "closed_form_ik", None)
    if closed is not None:
        solutions = closed(T, q_ref)
        if solutions is not None:
            return np.asarray(solutions[0], dtype=float) if solutions else None
    return np.asarray(result.q, dtype=float) if result.ok else None


def reach_window(kin: KinematicModel, point_at: Callable[[float], Vec], grasp: BeltGrasp, hover_m: float,
                 q_ref: Vec, length_m: float, start_along_m: float, max_reach_m: float = 0.78) -> ReachWindow:
    """The stretch of belt around ``start_along_m`` where the grasp (of an object whose centroid is
    ``point_at(along)``) and its hover pose are both reachable, walking the arm's configurations from ``q_ref``
    outwards without a branch change, and the grasp no further than ``max_reach_m`` from the base's z axis."""
    samples = np.arange(0.0, length_m + 1e-9, _WINDOW_STEP_M)
    k0 = int(np.argmin(np.abs(samples - start_along_m)))
    q_at: dict[int, Vec] = {}

    def ok(k: int, seed: Vec, first: bool = False) -> Vec | None:
        centroid = point_at(float(samples[k]))
        if float(np.hypot(*grasp.T_at(centroid)[:2, 3])) > max_reach_m:
            return None
        q_hover = nearest_ik(kin, grasp.T_at(centroid, hover_m), seed)
        if q_hover is None or (not first and float(np.max(np.abs(q_hover - seed))) > _BRANCH_JUMP_RAD):
            return None
        q_grasp = nearest_ik(kin, grasp.T_at(centroid), q_hover)
        if q_grasp is None or float(np.max(np.abs(q_grasp - q_hover))) > _BRANCH_JUMP_RAD:
            return None
        return q_hover

    first = ok(k0, np.asarray(q_ref, dtype=float), first=True)
    if first is None:
        return ReachWindow(0.0, 0.0, np.zeros(0), np.zeros((0, 6)))
    q_at[k0] = first
    lo = hi = k0
    for step in (-1, 1):
        k, seed = k0 + step, first
        while 0 <= k < len(samples):
            q = ok(k, seed)
            if q is None:
                break
            q_at[k], seed = q, q
            lo, hi = min(lo, k), max(hi, k)
            k += step
    keys = sorted(q_at)
    return ReachWindow(float(samples[lo]), float(samples[hi]), samples[keys], np.array([q_at[k] for k in keys]))


@dataclass(frozen=True)
class ArmState:
    """Where the arm is commanded to be now: joint positions, velocities and accelerations."""

    q: Vec
    qd: Vec
    qdd: Vec

    @classmethod
    def at_rest(cls, q: Vec) -> ArmState:
        return cls(np.asarray(q, dtype=float), np.zeros(6), np.zeros(6))


@dataclass(frozen=True)
class Approach:
    """The arm's way to the intercept: a jerk-limited trajectory from ``start_s`` (the run's time) that reaches
    ``q_arrive`` moving at ``qd_arrive`` (the tool at the belt's velocity) at ``arrive_s``; ``along_m`` is where
    along the belt the object's centroid is then."""

    start_s: float
    arrive_s: float
    along_m: float
    q_arrive: Vec
    qd_arrive: Vec
    trajectory: ruckig.Trajectory
    centroid_m: Vec  # where the object's centroid was predicted at the arrival when this was planned

    def sample(self, t_s: float) -> ArmState:
        """The commanded state at ``t_s`` (held at the arrival state after it)."""
        tau = min(max(t_s - self.start_s, 0.0), self.trajectory.duration)
        q, qd, qdd = self.trajectory.at_time(tau)
        return ArmState(np.asarray(q, dtype=float), np.asarray(qd, dtype=float), np.asarray(qdd, dtype=float))


class InterceptPlanner:
    """Chooses intercepts for one grasp of one tracked object (see the module docstring).

    ``centroid_at(t)`` is the motion model's predicted centroid at time ``t``; ``velocity`` the belt's velocity
    (base frame, m/s); ``window`` the reach window of this grasp (:func:`reach_window`, with ``along`` measured by
    ``along_of``)."""

    def __init__(self, kin: KinematicModel, grasp: BeltGrasp, window: ReachWindow, settings: InterceptSettings,
                 along_of: Callable[[Vec], float]) -> None:
        self.kin = kin
        self.grasp = grasp
        self.window = window
        self.s = settings
        self.along_of = along_of

    def _limits(self, inp: ruckig.InputParameter) -> None:
        s = self.s
        inp.max_velocity = [s.max_velocity_rad_s] * 6
        inp.max_acceleration = [s.max_acceleration_rad_s2] * 6
        inp.max_jerk = [s.max_jerk_rad_s3] * 6

    def arrival(self, centroid_m: Vec, velocity_m_s: Vec) -> tuple[Vec, Vec] | None:
        """The arm's configuration with the tool ``hover_m`` above the grasp of an object at ``centroid_m``, and the
        joint velocity that moves the tool at ``velocity_m_s`` there; None when out of reach."""
        seed = self.window.seed_at(self.along_of(centroid_m))
        T = self.grasp.T_at(centroid_m, self.s.hover_m)
        q = nearest_ik(self.kin, T, seed)
        if q is None:
            return None
        T_next = T.copy()
        T_next[:3, 3] += np.asarray(velocity_m_s, dtype=float) * _FD_S
        q_next = nearest_ik(self.kin, T_next, q)
        if q_next is None:
            return None
        return q, (q_next - q) / _FD_S

    def _trajectory(self, state: ArmState, q: Vec, qd: Vec, duration_s: float | None) -> ruckig.Trajectory | None:
        inp = ruckig.InputParameter(6)
        inp.current_position = state.q.tolist()
        inp.current_velocity = state.qd.tolist()
        inp.current_acceleration = state.qdd.tolist()
        inp.target_position = q.tolist()
        inp.target_velocity = qd.tolist()
        inp.target_acceleration = [0.0] * 6
        self._limits(inp)
        if duration_s is not None:
            inp.minimum_duration = float(duration_s)
        trajectory = ruckig.Trajectory(6)
        try:
            result = ruckig.Ruckig(6).calculate(inp, trajectory)
        except (RuntimeError, ruckig.RuckigError):  # a target velocity beyond the limits, ...
            return None
        return trajectory if result in (ruckig.Result.Working, ruckig.Result.Finished) else None

    def _clear(self, trajectory: ruckig.Trajectory, arrive_z_m: float) -> bool:
        """The tcp stays above the arrival height (less the clearance) all the way."""
        floor = arrive_z_m - self.s.clearance_m
        for tau in np.linspace(0.0, trajectory.duration, 12):
            q, _, _ = trajectory.at_time(float(tau))
            if float(self.kin.fk(np.asarray(q, dtype=float))[2, 3]) < floor:
                return False
        return True

    def fits_window(self, along_arrive_m: float, speed_m_s: float) -> bool:
        """The whole match, from the arrival at ``along_arrive_m``, lies inside the reach window."""
        w, m = self.window, self.s.margin_m
        end = along_arrive_m + abs(speed_m_s) * self.s.match_travel_s()
        return w.lo + m <= along_arrive_m and end <= w.hi - m

    def _attempt(self, now_s: float, state: ArmState, t_arrive: float, centroid_at: Callable[[float], Vec],
                 velocity_m_s: Vec, slack: float) -> Approach | None:
        """The approach arriving at ``t_arrive``, or None when it is not feasible (see the module docstring)."""
        centroid = centroid_at(t_arrive)
        along = self.along_of(centroid)
        if not self.fits_window(along, float(np.linalg.norm(velocity_m_s))):
            return None
        target = self.arrival(centroid, velocity_m_s)
        if target is None:
            return None
        q, qd = target
        shortest = self._trajectory(state, q, qd, None)
        if shortest is None or shortest.duration * slack > t_arrive - now_s + 1e-6:
            return None
        trajectory = self._trajectory(state, q, qd, t_arrive - now_s)
        # a duration ruckig cannot stretch to exactly (a blocked interval) would arrive late: not this time
        if trajectory is None or abs(trajectory.duration - (t_arrive - now_s)) > 1e-3:
            return None
        if not self._clear(trajectory, float(self.grasp.T_at(centroid, self.s.hover_m)[2, 3])):
            return None
        return Approach(now_s, t_arrive, along, q, qd, trajectory, np.asarray(centroid, dtype=float))

    def _too_late(self, t_arrive: float, centroid_at: Callable[[float], Vec]) -> bool:
        return self.along_of(centroid_at(t_arrive)) > self.window.hi

    def plan(self, now_s: float, state: ArmState, centroid_at: Callable[[float], Vec], velocity_m_s: Vec,
             arrive_s: float | None = None) -> Approach | None:
        """The approach to the earliest feasible intercept (or, re-planning, to the one at ``arrive_s`` or a few
        hundredths of a second from it when that is still feasible: a re-plan keeps its time); None when none is
        left. Arrival times are tried every 0.1 s, then every ``step_s`` before the first feasible one."""
        s = self.s
        if arrive_s is not None:
            for shift in (0.0, s.step_s, -s.step_s, 2 * s.step_s, -2 * s.step_s):
                t = arrive_s + shift
                if t - now_s >= s.earliest_s:
                    kept = self._attempt(now_s, state, t, centroid_at, velocity_m_s, 1.0)
                    if kept is not None:
                        return kept
        coarse = 0.1
        t, previous = now_s + s.earliest_s, None
        while t <= now_s + s.horizon_s and not self._too_late(t, centroid_at):
            found = self._attempt(now_s, state, t, centroid_at, velocity_m_s, s.slack)
            if found is not None:
                if previous is not None:  # the earliest between the last infeasible coarse time and this one
                    fine = previous + s.step_s
                    while fine < t - 1e-9:
                        earlier = self._attempt(now_s, state, fine, centroid_at, velocity_m_s, s.slack)
                        if earlier is not None:
                            return earlier
                        fine += s.step_s
                return found
            previous, t = t, t + coarse
        return None
