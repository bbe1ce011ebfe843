"""Depth image -> point cloud (camera frame) -> base frame, region-of-interest crop, open3d filtering.

Points keep the pixel they came from (``pixels``: (N, 2) int32 of u, v), so a cluster maps back onto the
colour image exactly (the colour and depth images are aligned, as the D435's aligned stream is).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, inv, transform_points
from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.perception.config import CloudSettings, RegionOfInterest

Points = NDArray[np.float64]


@dataclass(frozen=True)
class PixelCloud:
    """Points (N, 3) in some frame with the (u, v) pixel each came from."""

    points: Points
    pixels: NDArray[np.int32]

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def select(self, mask: NDArray[np.bool_] | NDArray[np.intp]) -> PixelCloud:
        return PixelCloud(self.points[mask], self.pixels[mask])


_GRID_CACHE: dict[tuple[int, int, float, float, float, float], tuple[NDArray[np.float32], NDArray[np.float32]]] = {}


def _ray_grid(intr: CameraIntrinsics) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    key = (intr.width_px, intr.height_px, intr.fx_px, intr.fy_px, intr.cx_px, intr.cy_px)
    grid = _GRID_CACHE.get(key)
    if grid is None:
        u = (np.arange(intr.width_px, dtype=np.float32) - np.float32(intr.cx_px)) / np.float32(intr.fx_px)
        v = (np.arange(intr.height_px, dtype=np.float32) - np.float32(intr.cy_px)) / np.float32(intr.fy_px)
        grid = (u, v)
        if len(_GRID_CACHE) > 8:
            _GRID_CACHE.clear()
        _GRID_CACHE[key] = grid
    return grid


def valid_depth_mask(depth_m: NDArray[np.float32], settings: CloudSettings) -> NDArray[np.bool_]:
    d = depth_m
    return np.isfinite(d) & (d >= settings.min_depth_m) & (d <= settings.max_depth_m)


def depth_to_cloud(depth_m: NDArray[np.float32], intr: CameraIntrinsics, valid: NDArray[np.bool_]) -> PixelCloud:
    """Back-project the valid pixels through the pinhole model (OpenCV axes: x right, y down, z forward)."""
    rows, cols = np.nonzero(valid)
    z = depth_m[rows, cols].astype(np.float64)
    u_ray, v_ray = _ray_grid(intr)
    pts = np.empty((z.shape[0], 3), dtype=np.float64)
    pts[:, 0] = u_ray[cols] * z
    pts[:, 1] = v_ray[rows] * z
    pts[:, 2] = z
    pixels = np.stack([cols, rows], axis=1).astype(np.int32)
    return PixelCloud(pts, pixels)


def to_base(cloud: PixelCloud, T_base_camera: Mat4) -> PixelCloud:
    """Transform column by column (a (N, 3) @ (3, 3) product is slow and erratic through BLAS threads)."""
    p, R, t = cloud.points, T_base_camera[:3, :3], T_base_camera[:3, 3]
    out = np.empty_like(p)
    for i in range(3):
        out[:, i] = R[i, 0] * p[:, 0] + R[i, 1] * p[:, 1] + R[i, 2] * p[:, 2] + t[i]
    return PixelCloud(out, cloud.pixels)


def roi_pixel_window(
    roi: RegionOfInterest, T_base_camera: Mat4, intr: CameraIntrinsics
) -> tuple[int, int, int, int] | None:
    """Pixel rectangle (u0, v0, u1, v1), end exclusive, holding the ROI box's image; None if not bounded
    (a corner behind the camera) or empty."""
    corners = np.array([[x, y, z] for x in roi.x_m for y in roi.y_m for z in roi.z_m], dtype=float)
    cam = transform_points(inv(T_base_camera), corners)
    if np.any(cam[:, 2] <= 1e-3):
        return None
    u = intr.fx_px * cam[:, 0] / cam[:, 2] + intr.cx_px
    v = intr.fy_px * cam[:, 1] / cam[:, 2] + intr.cy_px
    u0, u1 = max(0, int(np.floor(u.min()))), min(intr.width_px, int(np.ceil(u.max())) + 1)
    v0, v1 = max(0, int(np.floor(v.min()))), min(intr.height_px, int(np.ceil(v.max())) + 1)
    if u0 >= u1 or v0 >= v1:
        return u0, v0, u0, v0
    return u0, v0, u1, v1


def crop_roi(cloud: PixelCloud, roi: RegionOfInterest) -> PixelCloud:
    p = cloud.points
    keep = (
        (p[:, 0] >= roi.x_m[0]) & (p[:, 0] <= roi.x_m[1])
        & (p[:, 1] >= roi.y_m[0]) & (p[:, 1] <= roi.y_m[1])
        & (p[:, 2] >= roi.z_m[0]) & (p[:, 2] <= roi.z_m[1])
    )
    return cloud.select(keep)


def to_o3d(points: Points) -> o3d.geometry.PointCloud:
    pcd = o3d.geometry.PointCloud()
    pcd.points = o3d.utility.Vector3dVector(np.ascontiguousarray(points, dtype=np.float64))
    return pcd


def downsample(points: Points, voxel_m: float) -> o3d.geometry.PointCloud:
    return to_o3d(points).voxel_down_sample(voxel_m)


def remove_outliers(pcd: o3d.geometry.PointCloud, settings: CloudSettings) -> o3d.geometry.PointCloud:
    if len(pcd.points) <= settings.outlier_neighbors:
        return pcd
    filtered, _ = pcd.remove_statistical_outlier(settings.outlier_neighbors, settings.outlier_std_ratio)
    return filtered
