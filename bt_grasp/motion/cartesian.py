"""Straight-line tool motions (the final approach, the lift): IK along an interpolated tcp pose.

The tcp position is interpolated linearly and its orientation by slerp, in steps of at most
``step_m`` / ``step_rad``; each waypoint's IK starts from the previous solution (one seed, so the arm
moves continuously). A segment is refused, as a result value, when a waypoint is unreachable, when any
joint jumps more than ``max_joint_step_rad`` between waypoints (a wrist flip or a singularity), or when
a waypoint or the joint path between them collides with the planning scene. The object being grasped
goes into the scene as ``allowed_object`` so that the fingers may reach it.
"""

from __future__ import annotations

import enum
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

from bt_grasp.geometry import Mat4, make_T, rotation_angle_rad
from bt_grasp.motion.collision import FINE_RESOLUTION_RAD, collision_checker
from bt_grasp.motion.kinematics import IKOptions, KinematicModel, default_kinematics, is_rigid_transform
from bt_grasp.motion.planning_scene import PlanningScene

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]


class CartesianStatus(enum.Enum):
    OK = "ok"
    UNREACHABLE = "unreachable"  # a waypoint has no IK solution near the previous one
    JOINT_JUMP = "joint_jump"  # a joint moved more than the bound between two waypoints
    COLLISION = "collision"  # the start, a waypoint or the motion between waypoints collides
    INVALID_INPUT = "invalid_input"


@dataclass(frozen=True)
class CartesianOptions:
    step_m: float = 0.005  # largest tcp translation between waypoints
    step_rad: float = 0.05  # largest tcp rotation between waypoints
    max_joint_step_rad: float = 0.2  # largest change of any joint between waypoints
    margin_m: float = 0.0  # clearance to scene shapes (an approach ends close to the table)
    check_resolution_rad: float = FINE_RESOLUTION_RAD


@dataclass(frozen=True)
class CartesianResult:
    status: CartesianStatus
    path: Vec = field(default_factory=lambda: np.zeros((0, 6)))  # (N, 6), first row is q_start
    fraction: float = 0.0  # share of the segment that was feasible before it was refused
    message: str = ""
    compute_time_s: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status is CartesianStatus.OK


def offset_along_tool_z(T_base_tcp: Mat4, distance_m: float) -> Mat4:
    """The pose moved ``distance_m`` along its own z (the approach axis); negative backs away."""
    T = np.array(T_base_tcp, dtype=float)
    T[:3, 3] += distance_m * T[:3, 2]
    return T


def offset_in_base(T_base_tcp: Mat4, xyz_m: Vec | list[float]) -> Mat4:
    """The pose translated by ``xyz_m`` in the base frame (a lift is ``[0, 0, 0.15]``)."""
    return make_T(np.asarray(T_base_tcp)[:3, :3], np.asarray(T_base_tcp)[:3, 3] + np.asarray(xyz_m, dtype=float))


def cartesian_path(q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                   options: CartesianOptions | None = None, kin: KinematicModel | None = None) -> CartesianResult:
    """Joint waypoints that move the tcp on a straight line from ``fk(q_start)`` to the goal pose."""
    opts = options or CartesianOptions()
    kin = kin or default_kinematics()
    t0 = time.perf_counter()
    q0 = np.asarray(q_start, dtype=float).reshape(-1)
    if q0.shape != (6,) or not np.all(np.isfinite(q0)) or not is_rigid_transform(T_base_tcp_goal):
        return CartesianResult(CartesianStatus.INVALID_INPUT, message="bad start configuration or goal pose")
    if not (opts.step_m > 0 and opts.step_rad > 0 and opts.max_joint_step_rad > 0):
        return CartesianResult(CartesianStatus.INVALID_INPUT, message="steps and bounds must be positive")
    checker = collision_checker(scene, float(opts.margin_m), kin.opening_m, kin.urdf_path)
    if not checker.is_valid(q0):
        return CartesianResult(CartesianStatus.COLLISION, message=f"start collides: {checker.colliding_pairs(q0)}")
    T_start = kin.fk(q0)
    T_goal = np.asarray(T_base_tcp_goal, dtype=float)
    distance = float(np.linalg.norm(T_goal[:3, 3] - T_start[:3, 3]))
    angle = rotation_angle_rad(T_start[:3, :3], T_goal[:3, :3])
    n = max(1, math.ceil(max(distance / opts.step_m, angle / opts.step_rad)))
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([T_start[:3, :3], T_goal[:3, :3]])))
    ik_options = IKOptions(max_iterations=100)
    path = [q0]
    for k in range(1, n + 1):
        s = k / n
        T_k = make_T(slerp([s]).as_matrix()[0], (1 - s) * T_start[:3, 3] + s * T_goal[:3, 3])
        result = kin.ik(T_k, path[-1], seeds=1, options=ik_options)
        fraction = (k - 1) / n
        elapsed = time.perf_counter() - t0
        if not result.ok:
            return _refuse(CartesianStatus.UNREACHABLE, path, fraction, f"waypoint {k}/{n} unreachable", elapsed)
        jump = float(np.max(np.abs(result.q - path[-1])))
        if jump > opts.max_joint_step_rad:
            return _refuse(CartesianStatus.JOINT_JUMP, path, fraction,
                           f"joint step {jump:.3f} rad at waypoint {k}/{n}", elapsed)
        if not checker.is_valid(result.q):
            return _refuse(CartesianStatus.COLLISION, path, fraction,
                           f"waypoint {k}/{n} collides: {checker.colliding_pairs(result.q)}", elapsed)
        path.append(result.q)
    qs = np.stack(path)
    check = checker.check_path(qs, opts.check_resolution_rad)
    if not check.ok:
        seg = check.first_invalid_segment or 0
        return _refuse(CartesianStatus.COLLISION, path[: seg + 1], seg / n,
                       f"motion between waypoints {seg} and {seg + 1} collides", time.perf_counter() - t0)
    return CartesianResult(CartesianStatus.OK, qs, 1.0, f"{n} steps", time.perf_counter() - t0)


def _refuse(status: CartesianStatus, path: list[Vec], fraction: float, message: str,
            elapsed: float) -> CartesianResult:
    log.info("cartesian segment refused: %s: %s", status.value, message)
    return CartesianResult(status, np.stack(path), fraction, message, elapsed)
