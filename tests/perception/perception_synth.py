"""Synthetic RGB-D frames for unit tests: a table plane and upright boxes, ray-cast analytically (no simulator)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, make_T, rot_z
from bt_grasp.interfaces import CameraIntrinsics, RGBDFrame

INTRINSICS = CameraIntrinsics(640, 480, 625.0, 625.0, 319.5, 239.5)
WOOD = (171, 155, 130)
RED = (199, 66, 70)


@dataclass(frozen=True)
class Box:
    centre_xy: tuple[float, float]
    size: tuple[float, float, float]  # x, y, z in the box frame
    yaw_rad: float = 0.0
    rgb: tuple[int, int, int] = RED


def look_at(position: NDArray[np.float64], target: NDArray[np.float64]) -> Mat4:
    """OpenCV optical frame at ``position`` looking at ``target``, image down towards -z."""
    z = target - position
    z = z / np.linalg.norm(z)
    x = np.cross(np.array([0.0, 0.0, -1.0]), z)
    x /= np.linalg.norm(x)
    return make_T(np.stack([x, np.cross(z, x), z], axis=1), position)


DEFAULT_T_BASE_CAMERA = look_at(np.array([1.05, 0.0, 0.75]), np.array([0.45, 0.0, 0.0]))


def render(boxes: list[Box], T_base_camera: Mat4 = DEFAULT_T_BASE_CAMERA, table_z: float = 0.0,
           noise_m: float = 0.0, seed: int = 0) -> RGBDFrame:
    """Depth along the optical axis and RGB for a table at ``table_z`` (infinite plane) and upright boxes."""
    intr = INTRINSICS
    u, v = np.meshgrid(np.arange(intr.width_px), np.arange(intr.height_px))
    rays_cam = np.stack([(u - intr.cx_px) / intr.fx_px, (v - intr.cy_px) / intr.fy_px, np.ones(u.shape)], -1)
    R, origin = T_base_camera[:3, :3], T_base_camera[:3, 3]
    rays = rays_cam @ R.T  # base frame directions, scaled so the optical-axis component is 1
    t_best = np.full(u.shape, np.inf)
    color = np.zeros((*u.shape, 3), dtype=np.uint8)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_table = (table_z - origin[2]) / rays[..., 2]
    hit = t_table > 0
    t_best[hit] = t_table[hit]
    color[hit] = WOOD
    for box in boxes:
        T_base_box = make_T(rot_z(box.yaw_rad), [box.centre_xy[0], box.centre_xy[1], table_z + box.size[2] / 2])
        Rb = T_base_box[:3, :3]
        o = Rb.T @ (origin - T_base_box[:3, 3])
        d = rays @ Rb
        half = np.asarray(box.size) / 2
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (-half - o) / d
            t2 = (half - o) / d
        t_near = np.nanmax(np.minimum(t1, t2), axis=-1)
        t_far = np.nanmin(np.maximum(t1, t2), axis=-1)
        hit = (t_near <= t_far) & (t_near > 0) & (t_near < t_best)
        t_best[hit] = t_near[hit]
        color[hit] = box.rgb
    depth = np.where(np.isfinite(t_best), t_best, 0.0).astype(np.float32)  # ray z-component is 1: t = depth
    if noise_m > 0:
        rng = np.random.default_rng(seed)
        depth = np.where(depth > 0, depth + rng.normal(0.0, noise_m, depth.shape), 0.0).astype(np.float32)
    return RGBDFrame(color=color, depth_m=depth, intrinsics=intr, stamp_ns=0, mount="eye-to-hand")
