"""Time parametrisation of joint paths with ruckig (community version): jerk-limited, sampled at 100 Hz.

The community ruckig computes state-to-state trajectories; waypoints need ruckig Pro. So a path is
chained segment by segment, one ruckig trajectory per segment:

* ``blend=False`` (default, for planned paths): every segment goes from rest to rest with *phase*
  synchronisation, so all joints move proportionally and the motion follows the straight joint-space
  segment exactly: the path the planner checked for collisions is the path executed. The arm stops
  briefly at each waypoint; simplified plans have few waypoints, so that costs little.
* ``blend=True`` (for dense paths such as Cartesian segments): the arm passes interior waypoints with
  velocities from a heuristic (per joint: zero where the direction reverses, else the slower of the two
  neighbouring segments' nominal speeds, capped by what the acceleration allows) and *time*
  synchronisation. The motion then deviates slightly from the straight segments;
  ``Trajectory.max_path_deviation_rad`` reports by how much, and callers re-check the samples.

Limits (velocity, acceleration, jerk) hold at every instant: ruckig guarantees them per segment and
segments join with equal velocity and zero acceleration.
"""

from __future__ import annotations

import bisect
import functools
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import ruckig
from numpy.typing import NDArray

from bt_grasp.errors import BtGraspError
from bt_grasp.robot_description import arm_joint_limits

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]

CONTROL_RATE_HZ = 100.0


class TrajectoryError(BtGraspError):
    """A path could not be time-parametrised (bad input or a ruckig failure)."""


@dataclass(frozen=True)
class MotionLimits:
    """Per-joint kinematic limits for trajectories (the same value for all six joints).

    The velocity is a conservative fraction of the UR5's 3.15 rad/s; it is further clipped to the URDF's
    velocity limits.
    """

    max_velocity_rad_s: float = 1.0
    max_acceleration_rad_s2: float = 2.5
    max_jerk_rad_s3: float = 15.0

    def __post_init__(self) -> None:
        for name in ("max_velocity_rad_s", "max_acceleration_rad_s2", "max_jerk_rad_s3"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"MotionLimits.{name} must be a positive number, got {value}")

    def scaled(self, factor: float) -> MotionLimits:
        """Velocity scaled by ``factor``, acceleration by factor^2 and jerk by factor^3 (a slower motion)."""
        return MotionLimits(self.max_velocity_rad_s * factor, self.max_acceleration_rad_s2 * factor**2,
                            self.max_jerk_rad_s3 * factor**3)

    def arrays(self) -> tuple[Vec, Vec, Vec]:
        urdf_velocity = np.array(arm_joint_limits().velocity_rad_s, dtype=float)
        v = np.minimum(np.full(6, self.max_velocity_rad_s), urdf_velocity)
        return v, np.full(6, self.max_acceleration_rad_s2), np.full(6, self.max_jerk_rad_s3)


@dataclass(frozen=True)
class Trajectory:
    """Samples of a joint trajectory at the control rate: ``times_s`` (N,), ``q``/``qd``/``qdd`` (N, 6)."""

    times_s: Vec
    q: Vec
    qd: Vec
    qdd: Vec
    limits: MotionLimits = field(default_factory=MotionLimits)
    waypoints: Vec = field(default_factory=lambda: np.zeros((0, 6)))
    compute_time_s: float = 0.0  # wall time ruckig took for all segments
    blended: bool = False  # interior waypoints passed moving (``time_parametrize(blend=True)``)

    @functools.cached_property
    def max_path_deviation_rad(self) -> float:
        """Largest distance of a sample from the waypoint polyline (0 unless blended). Computed when first
        asked: no run reads it, and it cost a pick ~10 ms of Python loops over every sample."""
        return _deviation(self.q, self.waypoints) if self.blended and len(self.waypoints) > 1 else 0.0

    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1]) if len(self.times_s) else 0.0

    @functools.cached_property
    def _times(self) -> list[float]:
        return [float(t) for t in self.times_s]

    @functools.cached_property
    def _stacked(self) -> Vec:
        """q, qd and qdd side by side (N, 18): one interpolation per sample instead of three."""
        return np.hstack([self.q, self.qd, self.qdd])

    def sample(self, t_s: float) -> tuple[Vec, Vec, Vec]:
        """(q, qd, qdd) at time ``t_s``, linearly interpolated between samples, held after the end."""
        times = self._times
        t = min(max(float(t_s), 0.0), times[-1] if times else 0.0)
        k = bisect.bisect_right(times, t) - 1  # numpy's searchsorted(side="right") on the sorted times
        k = min(max(k, 0), len(times) - 1)
        if k == len(times) - 1:
            return self.q[k].copy(), self.qd[k].copy(), self.qdd[k].copy()
        dt = self.times_s[k + 1] - self.times_s[k]
        w = (t - self.times_s[k]) / dt if dt > 0 else 0.0
        a = self._stacked  # the same elementwise arithmetic as interpolating q, qd and qdd one by one
        out = a[k] + w * (a[k + 1] - a[k])
        return out[:6], out[6:12], out[12:]


#: waypoints where the path turns by more than this are passed at rest
CORNER_COS = math.cos(math.radians(25.0))


def _reachable(v0: float, d: float, a: float, j: float) -> float:
    """A speed safely reachable from ``v0`` over a distance ``d`` (acceleration and jerk bounded)."""
    by_acc = math.sqrt(v0**2 + a * d)
    # with zero acceleration at both ends, a speed change dv takes at least 2 sqrt(dv / j)
    lo, hi = v0, by_acc
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        duration = 2.0 * math.sqrt((mid - v0) / j)
        if duration * 0.5 * (v0 + mid) <= d:
            lo = mid
        else:
            hi = mid
    return lo


def _waypoint_velocities(path: Vec, v_max: Vec, a_max: Vec, j_max: Vec) -> Vec:
    """Pass-through velocities at waypoints (zero at both ends and at corners).

    The velocity at an interior waypoint is ``s * t``: ``t`` is the mean direction of the two
    neighbouring segments scaled to a largest component of 1 (so all joints stay in step), and the speed
    ``s`` (rad/s of the fastest joint) is capped by the velocity limit and, by a forward and a backward
    pass, by what half the acceleration and jerk limits reach over the neighbouring segments.
    """
    n = len(path)
    deltas = np.diff(path, axis=0)
    lengths = np.linalg.norm(deltas, axis=1)
    units = deltas / np.maximum(lengths, 1e-12)[:, None]
    tangents = np.zeros_like(path)
    speed = np.zeros(n)
    v_cap, a_cap, j_cap = float(np.min(v_max)), 0.5 * float(np.min(a_max)), 0.5 * float(np.min(j_max))
    for i in range(1, n - 1):
        if float(units[i - 1] @ units[i]) < CORNER_COS:
            continue
        t = units[i - 1] + units[i]
        tangents[i] = t / float(np.max(np.abs(t)))
        speed[i] = v_cap
    step = np.max(np.abs(deltas), axis=1)  # the fastest joint's travel per segment
    for i in range(1, n):
        speed[i] = min(speed[i], _reachable(speed[i - 1], step[i - 1], a_cap, j_cap))
    for i in range(n - 2, -1, -1):
        speed[i] = min(speed[i], _reachable(speed[i + 1], step[i], a_cap, j_cap))
    return tangents * speed[:, None]


def _deviation(samples: Vec, path: Vec) -> float:
    """Largest Euclidean distance of any sample from the polyline through ``path``."""
    worst = 0.0
    a, b = path[:-1], path[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    for q in samples:
        t = np.clip(np.einsum("ij,ij->i", q - a, ab) / denom, 0.0, 1.0)
        d = np.min(np.linalg.norm(a + t[:, None] * ab - q, axis=1))
        worst = max(worst, float(d))
    return worst


def time_parametrize(path: NDArray[np.float64], limits: MotionLimits | None = None, *,
                     rate_hz: float = CONTROL_RATE_HZ, blend: bool = False) -> Trajectory:
    """A jerk-limited trajectory through every waypoint of ``path`` (N, 6), sampled at ``rate_hz``.

    Starts and ends at rest. Raises :class:`TrajectoryError` for a malformed path or a ruckig failure.
    """
    limits = limits or MotionLimits()
    path = np.asarray(path, dtype=float)
    if path.ndim != 2 or path.shape[1] != 6 or len(path) < 1 or not np.all(np.isfinite(path)):
        raise TrajectoryError(f"a path is an (N, 6) array of finite joint angles, got shape {path.shape}")
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise TrajectoryError(f"the sample rate must be positive, got {rate_hz}")
    keep = [0] + [i for i in range(1, len(path)) if np.max(np.abs(path[i] - path[i - 1])) > 1e-9]
    path = path[keep]
    v_max, a_max, j_max = limits.arrays()
    velocities = _waypoint_velocities(path, v_max, a_max, j_max) if blend else np.zeros_like(path)
    segments: list[ruckig.Trajectory] = []
    t0 = time.perf_counter()
    otg = ruckig.Ruckig(6)
    for i in range(len(path) - 1):
        inp = ruckig.InputParameter(6)
        inp.current_position = path[i].tolist()
        inp.current_velocity = velocities[i].tolist()
        inp.current_acceleration = [0.0] * 6
        inp.target_position = path[i + 1].tolist()
        inp.target_velocity = velocities[i + 1].tolist()
        inp.target_acceleration = [0.0] * 6
        inp.max_velocity = v_max.tolist()
        inp.max_acceleration = a_max.tolist()
        inp.max_jerk = j_max.tolist()
        inp.synchronization = ruckig.Synchronization.Time if blend else ruckig.Synchronization.Phase
        segment = ruckig.Trajectory(6)
        result = otg.calculate(inp, segment)
        if result not in (ruckig.Result.Working, ruckig.Result.Finished):
            raise TrajectoryError(f"ruckig failed on segment {i}: {result}")
        segments.append(segment)
    compute_time = time.perf_counter() - t0
    starts = np.concatenate([[0.0], np.cumsum([s.duration for s in segments])])
    total = float(starts[-1])
    dt = 1.0 / rate_hz
    times = np.arange(0.0, total, dt)
    times = np.append(times, total) if (len(times) == 0 or total - times[-1] > 1e-9) else times
    q = np.empty((len(times), 6))
    qd = np.zeros_like(q)
    qdd = np.zeros_like(q)
    for n, t in enumerate(times):
        if not segments:
            q[n] = path[0]
            continue
        k = min(int(np.searchsorted(starts, t, side="right")) - 1, len(segments) - 1)
        pos, vel, acc = segments[k].at_time(float(t - starts[k]))
        q[n], qd[n], qdd[n] = pos, vel, acc
    q[-1], qd[-1], qdd[-1] = path[-1], 0.0, 0.0  # exactly at rest on the goal
    log.debug("trajectory: %d waypoints, %.3f s, ruckig %.2f ms", len(path), total, compute_time * 1e3)
    return Trajectory(times, q, qd, qdd, limits, path.copy(), compute_time, blended=blend)
