"""The twin controller's motion generators: what the joint drives are told at every physics step.

Each generator advances the *commanded* joint state (``target_q``/``target_qd`` in RTDE terms) by a time step,
as a UR controller plans from its own target rather than from the measured joints. ``movej`` and ``movel`` use
a trapezoidal speed profile on the leading joint (resp. the tool's path), the way URScript's ``movej(q, a, v)``
and ``movel(pose, a, v)`` are specified; ``servoj`` moves to each new target within the servo time; ``speedj``
ramps the joint speeds with the given acceleration; a stop decelerates the commanded speeds linearly to zero.
Pure numpy: no simulator, no clock of its own (the controller passes the time step).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Vec = NDArray[np.float64]
Mat4 = NDArray[np.float64]

#: UR5 joint speed limit used to clamp servo and speed targets (rad/s; the URDF's 3.15-3.2)
MAX_JOINT_SPEED_RAD_S = 3.14


class MotionError(Exception):
    """A motion the controller cannot carry out (an unreachable line, a target beyond the joint limits)."""


@dataclass(frozen=True)
class Profile:
    """A trapezoidal (or triangular) speed profile over a distance: ``sample(t)`` -> (s, ds/dt)."""

    distance: float
    speed: float
    accel: float

    @property
    def accel_time_s(self) -> float:
        if self.distance <= 0:
            return 0.0
        return min(self.speed / self.accel, math.sqrt(self.distance / self.accel))

    @property
    def duration_s(self) -> float:
        if self.distance <= 0:
            return 0.0
        ta = self.accel_time_s
        peak = self.accel * ta
        cruise = (self.distance - peak * ta) / peak if peak > 0 else 0.0
        return 2 * ta + max(0.0, cruise)

    def sample(self, t: float) -> tuple[float, float]:
        if self.distance <= 0:
            return 0.0, 0.0
        ta, total = self.accel_time_s, self.duration_s
        peak = self.accel * ta
        t = min(max(t, 0.0), total)
        if t < ta:
            return 0.5 * self.accel * t * t, self.accel * t
        if t <= total - ta:
            return 0.5 * peak * ta + peak * (t - ta), peak
        left = total - t
        return self.distance - 0.5 * self.accel * left * left, self.accel * left


def _profile(distance: float, speed: float, accel: float) -> Profile:
    if not (speed > 0 and accel > 0 and math.isfinite(speed) and math.isfinite(accel)):
        raise MotionError(f"speed {speed:g} and acceleration {accel:g} must be positive numbers")
    return Profile(distance, speed, accel)


class Motion:
    """The base: a motion that holds where it is. ``scaled``: the speed slider stretches its time."""

    scaled = False

    def __init__(self, q: Vec) -> None:
        self.q = np.array(q, dtype=float)
        self.qd = np.zeros(6)

    @property
    def done(self) -> bool:
        return True

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        return self.q, self.qd


class Hold(Motion):
    """Stand still at ``q``."""


class JointMove(Motion):
    """``movej``: every joint moves on one trapezoid, synchronised to the joint with the farthest to go."""

    scaled = True

    def __init__(self, q_start: Vec, q_goal: Vec, speed: float, accel: float) -> None:
        super().__init__(q_start)
        self.start = np.array(q_start, dtype=float)
        self.goal = np.array(q_goal, dtype=float)
        delta = self.goal - self.start
        reach = float(np.max(np.abs(delta)))
        self.direction = delta / reach if reach > 0 else np.zeros(6)
        self.profile = _profile(reach, speed, accel)
        self.t = 0.0

    @property
    def done(self) -> bool:
        return self.t >= self.profile.duration_s

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        self.t += dt
        s, sd = self.profile.sample(self.t)
        self.q = self.goal.copy() if self.done else self.start + self.direction * s
        self.qd = np.zeros(6) if self.done else self.direction * sd
        return self.q, self.qd


class LinearMove(Motion):
    """``movel``: the tool moves on a straight line (orientation by the shortest rotation) on one trapezoid over
    the path length, joints from inverse kinematics near the previous step. ``ik(T, q_near)`` returns None when
    a pose has no solution. Poses along the line (every 2 cm, at most 12, the ends included) are checked before
    the first step, so nothing moves toward an end out of reach; a pose between them without a solution raises
    :class:`MotionError` during the motion (the program then stops, as a controller's movel fails)."""

    scaled = True
    #: spacing of the pre-check along the line (m, rad), and at most this many poses (an IK costs ~0.6 ms: the
    #: check must fit in the controller's 8 ms cycle, or the cycle that starts a movel runs late)
    CHECK_STEP = 0.02
    MAX_CHECKS = 12

    def __init__(self, q_start: Vec, T_start: Mat4, T_goal: Mat4, speed: float, accel: float,
                 ik: Callable[[Mat4, Vec], Vec | None]) -> None:
        super().__init__(q_start)
        self.T0, self.T1 = np.array(T_start, dtype=float), np.array(T_goal, dtype=float)
        self.ik = ik
        self.dp = self.T1[:3, 3] - self.T0[:3, 3]
        self.axis, self.angle = rotation_between(self.T0[:3, :3], self.T1[:3, :3])
        length = float(np.linalg.norm(self.dp))
        # a pure rotation moves on the angle with the same numbers as rad/s and rad/s^2
        self.profile = _profile(length if length > 1e-6 else self.angle, speed, accel)
        self.total = self.profile.distance
        self.t = 0.0
        steps = min(self.MAX_CHECKS, max(2, int(max(length, self.angle) / self.CHECK_STEP) + 1))
        q = self.q
        for s in np.linspace(0.0, 1.0, steps):
            found = ik(self.pose_at(float(s)), q)
            if found is None:
                raise MotionError(f"movel: no inverse kinematics solution {float(s) * 100:.0f}% along the line")
            q = found

    def pose_at(self, s: float) -> Mat4:
        T = np.eye(4)
        T[:3, 3] = self.T0[:3, 3] + s * self.dp
        T[:3, :3] = axis_angle_matrix(self.axis, s * self.angle) @ self.T0[:3, :3]
        return T

    @property
    def done(self) -> bool:
        return self.t >= self.profile.duration_s

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        self.t += dt
        dist, _ = self.profile.sample(self.t)
        s = 1.0 if self.done or self.total <= 0 else dist / self.total
        q = self.ik(self.pose_at(s), self.q)
        if q is None:  # checked at the start: only a numerical corner case reaches this
            raise MotionError("movel: lost the inverse kinematics solution along the line")
        self.qd = np.zeros(6) if self.done else (q - self.q) / dt
        self.q = q
        return self.q, self.qd


class ServoMove(Motion):
    """``servoj``: go to the latest target within the servo time (speed clamped to the joints' limit), then hold
    it until the next target."""

    def __init__(self, q_start: Vec) -> None:
        super().__init__(q_start)
        self.target = self.q.copy()
        self.velocity = np.zeros(6)

    def retarget(self, q_target: Vec, servo_time_s: float) -> None:
        self.target = np.array(q_target, dtype=float)
        t = max(float(servo_time_s), 1e-3)
        velocity = (self.target - self.q) / t
        peak = float(np.max(np.abs(velocity)))
        if peak > MAX_JOINT_SPEED_RAD_S:
            velocity *= MAX_JOINT_SPEED_RAD_S / peak
        self.velocity = velocity

    @property
    def done(self) -> bool:
        return bool(np.allclose(self.q, self.target))

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        step = self.velocity * dt
        left = self.target - self.q
        arrive = np.abs(step) >= np.abs(left)
        self.q = np.where(arrive, self.target, self.q + step)
        self.qd = np.where(arrive, 0.0, self.velocity)
        return self.q, self.qd


class SpeedMove(Motion):
    """``speedj``: ramp the joint speeds toward the requested ones with the given acceleration (of the joint
    with the largest change; the others scaled to arrive together) and keep them."""

    def __init__(self, q_start: Vec, qd_start: Vec) -> None:
        super().__init__(q_start)
        self.qd = np.array(qd_start, dtype=float)
        self.wanted = self.qd.copy()
        self.accel = 1.0

    def retarget(self, qd_target: Vec, accel: float) -> None:
        wanted = np.array(qd_target, dtype=float)
        peak = float(np.max(np.abs(wanted)))
        if peak > MAX_JOINT_SPEED_RAD_S:
            wanted *= MAX_JOINT_SPEED_RAD_S / peak
        self.wanted = wanted
        self.accel = max(float(accel), 1e-3)

    @property
    def done(self) -> bool:
        return False

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        change = self.wanted - self.qd
        peak = float(np.max(np.abs(change)))
        if peak > self.accel * dt:
            change *= self.accel * dt / peak
        qd_new = self.qd + change
        self.q = self.q + 0.5 * (self.qd + qd_new) * dt
        self.qd = qd_new
        return self.q, self.qd


class Decelerate(Motion):
    """A stop: the commanded speeds fall linearly to zero over ``duration_s`` (all joints together)."""

    def __init__(self, q_start: Vec, qd_start: Vec, duration_s: float) -> None:
        super().__init__(q_start)
        self.v0 = np.array(qd_start, dtype=float)
        self.qd = self.v0.copy()
        self.duration = max(0.0, float(duration_s))
        self.t = 0.0

    @classmethod
    def joint(cls, q: Vec, qd: Vec, decel_rad_s2: float) -> Decelerate:
        """``stopj(a)``: the fastest joint slows at ``a``."""
        peak = float(np.max(np.abs(qd)))
        return cls(q, qd, peak / max(decel_rad_s2, 1e-6))

    @property
    def done(self) -> bool:
        return self.t >= self.duration

    def advance(self, dt: float) -> tuple[Vec, Vec]:
        if self.done:
            self.qd = np.zeros(6)
            return self.q, self.qd
        dt = min(dt, self.duration - self.t)
        t0, t1 = self.t, self.t + dt
        # v(t) = v0 (1 - t / T): integrate over [t0, t1]
        span = (t1 - t0) - (t1 * t1 - t0 * t0) / (2 * self.duration) if self.duration > 0 else 0.0
        self.q = self.q + self.v0 * span
        self.t = t1
        self.qd = self.v0 * (1 - self.t / self.duration) if self.duration > 0 and not self.done else np.zeros(6)
        return self.q, self.qd


# --- rotations -----------------------------------------------------------------------------------------
def axis_angle_matrix(axis: Vec, angle: float) -> NDArray[np.float64]:
    """Rodrigues: the rotation of ``angle`` rad about the unit ``axis``."""
    x, y, z = axis
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    R: NDArray[np.float64] = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K)
    return R


def rotation_vector(R: NDArray[np.float64]) -> Vec:
    """The rotation vector (axis * angle, angle in [0, pi]) of a rotation matrix, as UR poses carry it."""
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    sin = 0.5 * float(np.linalg.norm(w))
    angle = math.atan2(sin, (float(np.trace(R)) - 1.0) / 2.0)  # exact near 0 and near pi, unlike acos
    if angle < 1e-12:
        return np.zeros(3)
    if sin > 1e-6:
        return w / (2 * sin) * angle
    # near pi the antisymmetric part vanishes: the axis from the diagonal, signs from the symmetric part
    axis = np.sqrt(np.clip((np.diag(R) + 1.0) / 2.0, 0.0, None))
    i = int(np.argmax(axis))
    for j in range(3):
        if j != i:
            axis[j] = math.copysign(axis[j], R[i, j] + R[j, i])
    axis /= np.linalg.norm(axis)
    if float(axis @ w) < 0:  # just short of pi the antisymmetric part still tells the axis's sense
        axis = -axis
    return axis * angle


def rotation_between(R_a: NDArray[np.float64], R_b: NDArray[np.float64]) -> tuple[Vec, float]:
    """(unit axis, angle) of the rotation taking ``R_a`` to ``R_b`` in the base frame: ``R_b = R(axis, angle) R_a``."""
    vec = rotation_vector(R_b @ R_a.T)
    angle = float(np.linalg.norm(vec))
    return (vec / angle if angle > 0 else np.array([0.0, 0.0, 1.0])), angle


def pose_to_T(pose: Vec) -> Mat4:
    """A UR pose ``[x, y, z, rx, ry, rz]`` as a 4x4 transform."""
    p = np.asarray(pose, dtype=float)
    T = np.eye(4)
    T[:3, 3] = p[:3]
    angle = float(np.linalg.norm(p[3:6]))
    if angle > 0:
        T[:3, :3] = axis_angle_matrix(p[3:6] / angle, angle)
    return T


def T_to_pose(T: Mat4) -> Vec:
    """A 4x4 transform as a UR pose ``[x, y, z, rx, ry, rz]``."""
    return np.concatenate([np.asarray(T[:3, 3], dtype=float), rotation_vector(np.asarray(T[:3, :3]))])
