"""Synthetic RGB-D frames of a household mesh on a table, for unit tests of grasping from what a camera sees.

The table is the analytic plane of :mod:`perception_synth`; the mesh (a shipped household object, posed on the
table) is drawn by z-buffering a dense, seeded sample of its surface: each sample lands in its pixel and the
nearest wins. No simulator: the frame then goes through the real perception pipeline, so the detection (its
footprint, its visible points) is what Perceive would report of that object, and nothing else is known.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from perception_synth import DEFAULT_T_BASE_CAMERA, INTRINSICS, WOOD, Box, render

from bt_grasp.geometry import Mat4, make_T, rot_z
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import Detection

HOUSEHOLD = Path(__file__).resolve().parents[2] / "bt_grasp" / "assets" / "household"
GREY = (120, 120, 125)


def household_mesh(name: str) -> trimesh.Trimesh:
    mesh = trimesh.load(HOUSEHOLD / f"{name}.obj", force="mesh")
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def render_mesh(mesh: trimesh.Trimesh, T_table_object: Mat4, T_base_camera: Mat4 = DEFAULT_T_BASE_CAMERA,
                samples: int = 600_000, seed: int = 0) -> RGBDFrame:
    """The table and the mesh at ``T_table_object`` (base frame; the table is z = 0) seen by the camera."""
    table = render([], T_base_camera)
    points, _ = trimesh.sample.sample_surface(mesh, samples, seed=seed)
    T = np.asarray(T_table_object, dtype=float)
    pts_base = np.asarray(points) @ T[:3, :3].T + T[:3, 3]
    T_cam_base = np.linalg.inv(np.asarray(T_base_camera, dtype=float))
    cam = pts_base @ T_cam_base[:3, :3].T + T_cam_base[:3, 3]
    z = cam[:, 2]
    u = np.round(INTRINSICS.fx_px * cam[:, 0] / z + INTRINSICS.cx_px).astype(int)
    v = np.round(INTRINSICS.fy_px * cam[:, 1] / z + INTRINSICS.cy_px).astype(int)
    ok = (z > 0) & (u >= 0) & (u < INTRINSICS.width_px) & (v >= 0) & (v < INTRINSICS.height_px)
    u, v, z = u[ok], v[ok], z[ok]
    depth = np.asarray(table.depth_m, dtype=float).copy()
    depth[depth <= 0] = np.inf
    nearest = np.full(depth.shape, np.inf)
    np.minimum.at(nearest, (v, u), z)
    object_px = nearest < depth
    depth[object_px] = nearest[object_px]
    color = np.asarray(table.color).copy()
    color[object_px] = GREY
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    return RGBDFrame(color=color, depth_m=depth, intrinsics=INTRINSICS, stamp_ns=0, mount=table.mount)


def seen(name: str, xy: tuple[float, float] = (0.5, 0.0), yaw_deg: float = 0.0,
         R_rest: Mat4 | None = None) -> Detection:
    """Perceive's detection of household object ``name`` lying on the table at ``xy``, turned ``yaw_deg`` (and
    first turned by the rotation ``R_rest``, then set down on its lowest point)."""
    mesh = household_mesh(name)
    R = np.eye(3) if R_rest is None else np.asarray(R_rest, dtype=float)[:3, :3]
    lowest = float((np.asarray(mesh.vertices) @ R.T)[:, 2].min())
    T = make_T(rot_z(np.deg2rad(yaw_deg)) @ R, [xy[0], xy[1], 0.0])
    T[:3, 3] -= (rot_z(np.deg2rad(yaw_deg)) @ np.array([0.0, 0.0, lowest]))
    result = perceive(render_mesh(mesh, T), DEFAULT_T_BASE_CAMERA)
    assert result.ok and result.best is not None, result.message
    return result.best


__all__ = ["DEFAULT_T_BASE_CAMERA", "WOOD", "Box", "household_mesh", "render_mesh", "seen"]
