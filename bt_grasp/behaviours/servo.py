"""The pieces of visual following that are plain arithmetic: the target's track and the control law.

Position-based visual servoing (PBVS) with a PID on the position error and the target's velocity fed
forward. Why position-based: the measurement is already a 3-D point in the base frame (colour blob + depth,
or the top-face plane), the same for a fixed and a wrist camera, so one law serves both mounts; the tool
axis, not the camera's, must end up over the object, which image-based servoing (IBVS) of a wrist camera
offset 7 cm from the tool would have to correct for anyway; and the gains mean the same thing (1/s) in
every view. Velocity feed-forward matters for a moving target: a PID alone lags a target moving at v by
v / kp at steady state (5 cm/s with kp = 3/s: 17 mm) until the integral winds up; with the track's velocity
fed forward the PID only corrects the estimate's error.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

Vec3 = NDArray[np.float64]


@dataclass
class TargetTrack:
    """The followed target: recent measurements of its centre (base frame) and what it looks like.

    ``predict(t)`` fits a straight line through the last measurements (least squares, a constant-velocity
    model): position and velocity at time ``t``. Written to the blackboard so a second FollowTarget (a
    lower standoff, the grasp) continues where the first one left off.
    """

    color: str
    height_m: float  # the object's height (top face above its support), from the full perception
    yaw_rad: float  # the object's long-side direction about base +z
    length_m: float  # the object's long side, m
    width_m: float  # the object's narrow side, m
    round: bool
    window: int = 12
    samples: deque[tuple[float, Vec3]] = field(default_factory=deque)
    areas: deque[int] = field(default_factory=lambda: deque(maxlen=8))  # recent blob areas, px

    def add(self, t_s: float, centre_base_m: Vec3) -> None:
        self.samples.append((float(t_s), np.asarray(centre_base_m, dtype=float).copy()))
        while len(self.samples) > self.window:
            self.samples.popleft()

    @property
    def last_time_s(self) -> float:
        return self.samples[-1][0] if self.samples else float("-inf")

    @property
    def top_z_m(self) -> float:
        return float(self.samples[-1][1][2] + self.height_m / 2) if self.samples else float("nan")

    def predict(self, t_s: float) -> tuple[Vec3, Vec3]:
        """(position, velocity) at ``t_s``; velocity 0 until two measurements span some time."""
        times = np.array([s[0] for s in self.samples])
        points = np.array([s[1] for s in self.samples])
        if len(times) < 3 or times[-1] - times[0] < 1e-3:
            return points[-1].copy(), np.zeros(3)
        tc = times - times.mean()
        velocity = (tc[:, None] * (points - points.mean(axis=0))).sum(axis=0) / float((tc * tc).sum())
        velocity[2] = 0.0  # objects ride on a horizontal surface
        position = points.mean(axis=0) + velocity * (t_s - times.mean())
        position[2] = float(points[-1, 2])
        return position, velocity


@dataclass(frozen=True)
class Gains:
    kp: float  # 1/s: velocity command per metre of error
    ki: float  # 1/s^2
    kd: float  # dimensionless
    max_speed_m_s: float = 0.30
    max_descent_m_s: float = 0.10
    integral_limit_m_s: float = 0.02  # the integral term's share of the command is clamped to this
    integral_zone_m: float = 0.015  # the error is integrated only this close to the goal (no wind-up)


@dataclass
class PidLaw:
    """u = v_target + kp e + ki integral(e) + kd de/dt, limited; one call per control period."""

    gains: Gains
    integral: Vec3 = field(default_factory=lambda: np.zeros(3))
    last_error: Vec3 | None = None

    def command(self, error: Vec3, target_velocity: Vec3, dt_s: float) -> Vec3:
        g = self.gains
        if g.ki > 0 and float(np.linalg.norm(error)) < g.integral_zone_m:
            self.integral = self.integral + error * dt_s
            limit = g.integral_limit_m_s / g.ki
            self.integral = np.clip(self.integral, -limit, limit)
        derivative = np.zeros(3) if self.last_error is None else (error - self.last_error) / dt_s
        self.last_error = error.copy()
        u = target_velocity + g.kp * error + g.ki * self.integral + g.kd * derivative
        speed = float(np.linalg.norm(u[:2]))
        if speed > g.max_speed_m_s:
            u[:2] *= g.max_speed_m_s / speed
        u[2] = float(np.clip(u[2], -g.max_descent_m_s, g.max_descent_m_s))
        return u


def rotate_towards(R_now: NDArray[np.float64], R_goal: NDArray[np.float64], max_angle_rad: float
                   ) -> NDArray[np.float64]:
    """R_now turned towards R_goal by at most ``max_angle_rad`` (about the relative rotation's axis)."""
    import cv2

    R_rel = R_goal @ R_now.T
    rvec, _ = cv2.Rodrigues(R_rel)
    angle = float(np.linalg.norm(rvec))
    if angle <= max_angle_rad:
        return R_goal.copy()
    step, _ = cv2.Rodrigues(rvec * (max_angle_rad / angle))
    return np.asarray(step) @ R_now


def grasp_yaw(track: TargetTrack, current_yaw_rad: float) -> float:
    """The tool's yaw (tool x about base z) that closes the fingers (tool y) across the narrow side: of the
    two symmetric choices, the one nearer the current yaw. Round objects keep the current yaw."""
    if track.round:
        return current_yaw_rad
    base = track.yaw_rad  # tool x along the long side: tool y (closing) across it
    options = [base + k * np.pi for k in (-2, -1, 0, 1, 2)]
    return float(min(options, key=lambda a: abs(np.angle(np.exp(1j * (a - current_yaw_rad))))))
