"""The controller's kinematics in UR's own frames, from bt_grasp's arm model.

A UR controller reports poses in its ``base`` frame, which the ROS description (bt_grasp's URDF) places turned
by pi about z from ``base_link``, and of its TCP, an offset from the tool flange (``tool0``) the program sets
(``set_tcp``). Forward kinematics is bt_grasp's pinocchio model (``bt_grasp.motion.kinematics``); inverse
kinematics is its closed-form UR solver (``bt_grasp.motion.analytic_ik``), choosing the solution nearest the
given joints, as URScript's ``get_inverse_kin(x, qnear)`` does.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import inv
from bt_grasp.motion.kinematics import default_kinematics
from bt_grasp.robot_description import TOOL_LINK
from bt_grasp.sim.twin.motion import T_to_pose, pose_to_T

Vec = NDArray[np.float64]
Mat4 = NDArray[np.float64]

UR_BASE_LINK = "base"  # the UR controller's base frame in the ROS description


class UrKinematics:
    """FK/IK of the arm between UR's ``base`` frame and a TCP given as an offset from the flange."""

    def __init__(self) -> None:
        self.arm = default_kinematics()
        q0 = np.zeros(6)
        self.T_baselink_base: Mat4 = self.arm.fk_link(q0, UR_BASE_LINK)
        self.T_base_baselink: Mat4 = inv(self.T_baselink_base)
        # bt_grasp's own tcp, for its closed-form solver: T_tool0_btcp (constant)
        self.T_tool0_btcp: Mat4 = inv(self.arm.fk_link(q0, TOOL_LINK)) @ self.arm.fk(q0)
        self.T_btcp_tool0: Mat4 = inv(self.T_tool0_btcp)
        self.lower_rad, self.upper_rad = self.arm.lower_rad, self.arm.upper_rad

    def T_base_flange(self, q: Vec) -> Mat4:
        return self.T_base_baselink @ self.arm.fk_link(q, TOOL_LINK)

    def T_base_tcp(self, q: Vec, T_flange_tcp: Mat4) -> Mat4:
        return self.T_base_flange(q) @ T_flange_tcp

    def tcp_pose(self, q: Vec, T_flange_tcp: Mat4) -> Vec:
        return T_to_pose(self.T_base_tcp(q, T_flange_tcp))

    def ik(self, T_base_tcp: Mat4, T_flange_tcp: Mat4, q_near: Vec) -> Vec | None:
        """The joint solution reaching ``T_base_tcp`` closest to ``q_near`` (each joint within a turn of it), or
        None when the pose is out of reach or beyond the joint limits."""
        T_baselink_btcp = self.T_baselink_base @ T_base_tcp @ inv(T_flange_tcp) @ self.T_tool0_btcp
        solutions = self.arm.closed_form_ik(T_baselink_btcp, np.asarray(q_near, dtype=float))
        if not solutions:
            return None
        return np.asarray(solutions[0], dtype=float)

    def ik_pose(self, pose: Vec, T_flange_tcp: Mat4, q_near: Vec) -> Vec | None:
        return self.ik(pose_to_T(pose), T_flange_tcp, q_near)

    def within_limits(self, q: Vec) -> bool:
        q = np.asarray(q, dtype=float)
        return bool(q.shape == (6,) and np.all(np.isfinite(q)) and self.arm.within_limits(q))


def pose_trans(p_from: Vec, p_from_to: Vec) -> Vec:
    """URScript's ``pose_trans``: the second pose expressed through the first."""
    return T_to_pose(pose_to_T(p_from) @ pose_to_T(p_from_to))


def finite_pose(pose: Vec) -> bool:
    return len(pose) == 6 and all(math.isfinite(float(v)) for v in pose)
