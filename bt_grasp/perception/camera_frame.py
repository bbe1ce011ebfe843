"""Perception without a calibration: the table frame a single frame shows, so results can be given in the camera's.

The pipeline (:func:`bt_grasp.perception.pipeline.perceive`) works in a frame whose z axis is the table's normal: the
robot base frame, placed by the hand-eye calibration. A camera nobody calibrated yet (a user's first look at their
own table) has no base frame; :func:`table_frame` finds the largest plane facing the camera in the frame itself
(the table), and puts a frame on it: z along its normal towards the camera, x the camera's x projected onto it, the
origin where the optical axis meets it. The pipeline runs in that frame with a region of interest around its origin
(:func:`table_config`); the caller gives every result back in the camera's optical frame (``T_camera_table``).
Nothing about the robot is known then: grasps are ranked without the arm's reach.
"""

from __future__ import annotations

import numpy as np

from bt_grasp.geometry import Mat4, inv
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception import cloud as pc
from bt_grasp.perception.config import PerceptionConfig, RegionOfInterest
from bt_grasp.perception.segment import fit_table_plane

#: the table may lean this far from facing the camera (a camera looking down at 20 degrees above the table: 70)
MAX_TABLE_TILT_DEG = 75.0
#: half the side of the region of interest around the table frame's origin, m, and its height range
TABLE_HALF_SIDE_M = 0.40
TABLE_Z_M = (-0.03, 0.30)
#: the plane is fitted on this many points at most (every k-th valid pixel)
_PLANE_POINTS = 40000
#: camera axes -> a frame whose +z looks back at the camera (x kept, y and z flipped)
_R_UP_CAMERA = np.diag([1.0, -1.0, -1.0])


def table_frame(frame: RGBDFrame, config: PerceptionConfig) -> Mat4 | None:
    """``T_camera_table`` of the largest plane facing the camera, or None (no such plane, or the optical axis misses
    it). Deterministic: the plane's RANSAC is seeded (``segment.fit_table_plane``)."""
    depth = np.asarray(frame.depth_m, dtype=np.float32)
    valid = pc.valid_depth_mask(depth, config.cloud)
    count = int(valid.sum())
    if count < 100:
        return None
    step = max(1, count // _PLANE_POINTS)
    if step > 1:
        keep = np.zeros(valid.size, dtype=bool)
        keep[np.flatnonzero(valid)[::step]] = True
        valid = keep.reshape(valid.shape)
    points_cam = pc.depth_to_cloud(depth, frame.intrinsics, valid).points
    points_up = points_cam @ _R_UP_CAMERA.T
    settings = config.segmentation.model_copy(update={"plane_max_tilt_deg": MAX_TABLE_TILT_DEG})
    plane = fit_table_plane(pc.downsample(points_up, config.cloud.voxel_m), settings)
    if plane is None:
        return None
    normal_cam = _R_UP_CAMERA @ plane.normal  # the plane's normal, camera frame, pointing towards the camera
    offset = plane.offset  # n . p + offset = 0 for p in the up frame; the same offset in the camera frame
    if abs(normal_cam[2]) < 1e-6:
        return None
    t = -offset / normal_cam[2]  # the optical axis (0, 0, t) meets the plane
    if t <= 0:
        return None
    origin = np.array([0.0, 0.0, t])
    x = np.array([1.0, 0.0, 0.0]) - normal_cam[0] * normal_cam
    if np.linalg.norm(x) < 1e-6:
        return None
    x /= np.linalg.norm(x)
    y = np.cross(normal_cam, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, normal_cam, origin
    return T


def table_config(config: PerceptionConfig) -> PerceptionConfig:
    """``config`` with its region of interest around the table frame's origin (:data:`TABLE_HALF_SIDE_M`)."""
    side = (-TABLE_HALF_SIDE_M, TABLE_HALF_SIDE_M)
    return config.model_copy(update={"roi": RegionOfInterest(x_m=side, y_m=side, z_m=TABLE_Z_M)})


def pipeline_pose(T_camera_table: Mat4) -> Mat4:
    """What the pipeline takes as ``T_base_camera`` when it works in the table frame."""
    return inv(T_camera_table)
