"""Conversions between sapien.Pose and 4x4 transforms, and between SAPIEN's and OpenCV's camera axes."""

from __future__ import annotations

import numpy as np
import sapien

from bt_grasp.geometry import Mat4, T_from_pos_quat_wxyz, quat_wxyz

#: columns: OpenCV optical axes expressed in SAPIEN's camera axes (x forward, y left, z up)
R_SAPCAM_CV = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def to_T(pose: sapien.Pose) -> Mat4:
    return T_from_pos_quat_wxyz(pose.p, pose.q)


def to_pose(T: Mat4) -> sapien.Pose:
    q = quat_wxyz(T)
    return sapien.Pose(p=T[:3, 3].astype(np.float32), q=(q / np.linalg.norm(q)).astype(np.float32))


def sapien_cam_from_cv(T_parent_cv: Mat4) -> Mat4:
    """The SAPIEN camera pose whose optical (OpenCV) frame is T_parent_cv."""
    T = np.eye(4)
    T[:3, :3] = T_parent_cv[:3, :3] @ R_SAPCAM_CV.T
    T[:3, 3] = T_parent_cv[:3, 3]
    return T


def cv_from_sapien_cam(T_parent_sapcam: Mat4) -> Mat4:
    T = np.eye(4)
    T[:3, :3] = T_parent_sapcam[:3, :3] @ R_SAPCAM_CV
    T[:3, 3] = T_parent_sapcam[:3, 3]
    return T


def look_at_cv(position_m: np.ndarray, target_m: np.ndarray, roll_rad: float = 0.0) -> Mat4:
    """OpenCV optical frame at position looking at target, image 'down' towards world -z."""
    z = np.asarray(target_m, float) - np.asarray(position_m, float)
    z /= np.linalg.norm(z)
    world_down = np.array([0.0, 0.0, -1.0])
    x = np.cross(world_down, z)
    if np.linalg.norm(x) < 1e-6:  # looking straight down: image x along world -y
        x = np.array([0.0, -1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z], axis=1)
    if roll_rad:
        c, s = np.cos(roll_rad), np.sin(roll_rad)
        R = R @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = position_m
    return T
