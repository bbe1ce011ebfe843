"""An object's surface as perception saw it, in the robot BASE frame: points with outward normals (issue 28).

What antipodal grasp sampling (:mod:`bt_grasp.perception.antipodal`) works on. A detection's visible points
(normals estimated by PCA of their neighbours, thinned to a voxel grid) together with the surface of the
shape perception fitted to it, which stands in for the sides the camera cannot see; and points on known boxes
(fixtures) for clearance. Never the simulator's mesh or pose.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.perception import results


@dataclass(frozen=True)
class ObjectCloud:
    """An object's observed surface in the BASE frame: points (N, 3) and outward unit normals (N, 3)."""

    points_base_m: NDArray[np.float64]
    normals_base: NDArray[np.float64]

    @property
    def centre_of_mass_estimate(self) -> NDArray[np.float64]:
        """The centre of the cloud's axis-aligned extent: a solid object's centre, seen from any side."""
        lo, hi = self.points_base_m.min(axis=0), self.points_base_m.max(axis=0)
        return np.asarray((lo + hi) / 2, dtype=float)


def estimate_normals(points: NDArray[np.float64], k: int = 12,
                     viewpoint_base_m: Sequence[float] | None = None) -> NDArray[np.float64]:
    """Unit normals by PCA of each point's k nearest neighbours. With ``viewpoint_base_m`` (the camera that saw
    the points) each is turned towards it: a surface the camera sees faces it, so this is outward for any
    object, concave ones too (a bowl's or a mug's inner wall faces into its hollow). Without, turned away from
    the cloud's vertical axis (outward for a convex object only; a normal facing straight up or down keeps
    pointing up)."""
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=float)
    k = max(3, min(k, len(pts)))
    _, idx = cKDTree(pts).query(pts, k=k)
    nb = pts[idx] - pts[idx].mean(axis=1, keepdims=True)
    _, _, vt = np.linalg.svd(nb, full_matrices=False)
    normals = vt[:, -1, :]
    if viewpoint_base_m is not None:
        outward = np.asarray(viewpoint_base_m, dtype=float).reshape(1, 3) - pts
    else:
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        centre = (lo + hi) / 2
        outward = pts - centre
        outward[:, 2] = np.where(np.abs(normals[:, 2]) > 0.9, 1.0, outward[:, 2])
    flip = np.sum(normals * outward, axis=1) < 0
    normals[flip] *= -1
    return np.asarray(normals / np.linalg.norm(normals, axis=1, keepdims=True), dtype=float)


def seen_through(fitted_m: NDArray[np.float64], visible_m: NDArray[np.float64], viewpoint_base_m: Sequence[float],
                 near_m: float = 0.006, ray_m: float = 0.004, in_front_m: float = 0.008) -> NDArray[np.bool_]:
    """Which points of a fitted shape's surface the camera at ``viewpoint_base_m`` would have seen had they been
    there, but did not: no visible point within ``near_m`` of it, and none within ``ray_m`` of the line of sight
    to it (``in_front_m`` or more nearer the camera) that would hide it. Such a point is air: the corner a T or an
    L leaves empty, the hollow of a bowl under its rim's height. A hidden side (behind what was seen) is kept."""
    from scipy.spatial import cKDTree

    fitted = np.asarray(fitted_m, dtype=float)
    visible = np.asarray(visible_m, dtype=float)
    cam = np.asarray(viewpoint_base_m, dtype=float).reshape(3)
    near = cKDTree(visible).query(fitted, k=1, distance_upper_bound=near_m)[0] <= near_m
    out = np.zeros(len(fitted), dtype=bool)
    rel_v = visible - cam
    for start in range(0, len(fitted), 256):
        chunk = fitted[start:start + 256] - cam
        length = np.linalg.norm(chunk, axis=1)
        u = chunk / np.maximum(length, 1e-9)[:, None]
        t = u @ rel_v.T  # (B, M): how far along each line of sight each visible point lies
        perp2 = np.einsum("mj,mj->m", rel_v, rel_v)[None, :] - t**2
        hides = (perp2 < ray_m**2) & (t > 0.0) & (t < length[:, None] - in_front_m)
        out[start:start + 256] = ~hides.any(axis=1)
    return np.asarray(out & ~near, dtype=bool)


def extruded_footprint(points_m: NDArray[np.float64], table_z_m: float, cell_m: float = 0.003,
                       spacing_m: float = 0.005) -> ObjectCloud:
    """The sides the camera may not see, as the walls of the object's seen footprint: the cells (``cell_m``,
    seen from above) holding visible points (holes filled), their outer outline walled from the table up to the
    height seen there, with outward normals across the outline (the gradient of the smoothed footprint, so a
    wall at any yaw has its true direction, not a staircase's). Where a fitted box or cylinder completes only a
    convex footprint, this completes a T's stem, an L's leg or a mug's handle side; it assumes the walls go
    straight down from the outline (an object lying or standing on the table, as the fitted shapes do)."""
    from scipy.ndimage import binary_closing, binary_fill_holes, gaussian_filter, maximum_filter

    pts = np.asarray(points_m, dtype=float).reshape(-1, 3)
    lo = pts[:, :2].min(axis=0) - 4 * cell_m
    ij = np.floor((pts[:, :2] - lo) / cell_m).astype(int)
    shape = tuple(int(v) for v in ij.max(axis=0) + 5)
    height = np.full(shape, -np.inf)
    np.maximum.at(height, (ij[:, 0], ij[:, 1]), pts[:, 2])
    # holes filled: the outline only (inside a mug's rim the camera may see nothing: that is no wall)
    occupied = binary_fill_holes(binary_closing(np.isfinite(height), structure=np.ones((3, 3), dtype=bool)))
    top = maximum_filter(height, size=3, mode="constant", cval=-np.inf)
    padded = np.pad(occupied, 1)
    edge = occupied & ~(padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:])
    smooth = gaussian_filter(occupied.astype(float), sigma=1.5)
    gi, gj = np.gradient(smooth)
    ci, cj = np.nonzero(edge & np.isfinite(top))
    out_dir = -np.stack([gi[ci, cj], gj[ci, cj]], axis=1)
    norm = np.linalg.norm(out_dir, axis=1)
    ok = norm > 1e-9
    ci, cj, out_dir = ci[ok], cj[ok], out_dir[ok] / norm[ok, None]
    xy = lo + (np.stack([ci, cj], axis=1) + 0.5) * cell_m + 0.5 * cell_m * out_dir
    walls, normals = [], []
    for k in range(len(xy)):
        zs = np.arange(table_z_m + spacing_m / 2, top[ci[k], cj[k]], spacing_m)
        if len(zs):
            walls.append(np.column_stack([np.full(len(zs), xy[k, 0]), np.full(len(zs), xy[k, 1]), zs]))
            normals.append(np.tile([out_dir[k, 0], out_dir[k, 1], 0.0], (len(zs), 1)))
    if not walls:
        return ObjectCloud(np.zeros((0, 3)), np.zeros((0, 3)))
    wall_pts, wall_n = np.vstack(walls), np.vstack(normals)
    keep = voxel_indices(wall_pts, spacing_m)
    return ObjectCloud(wall_pts[keep], wall_n[keep])


def detection_cloud(det: results.Detection, spacing_m: float = 0.005,
                    viewpoint_base_m: Sequence[float] | None = None) -> ObjectCloud:
    """The object's surface as perception reported it, in the BASE frame: the surface of the fitted shape (the
    gravity-aligned box, or the upright cylinder of a round footprint; sides and top, never the bottom, which
    the table hides), which stands in for the sides the camera cannot see, together with the visible points
    when the detection carries them (``points_base_m``, normals estimated by :func:`estimate_normals`, turned
    towards ``viewpoint_base_m`` when given, then thinned to one per ``spacing_m`` voxel: a camera's ~1 mm
    sampling would only slow the search). With a viewpoint, the walls of the seen footprint
    (:func:`extruded_footprint`) complete what the fitted convex shape cannot (a T's stem; only walls farther
    than ``spacing_m`` from the fitted points kept are added: elsewhere a wall stands up to half a cell outside
    the fitted shape and would only widen the object), and every completed point the camera would have seen but
    did not is dropped (:func:`seen_through`): the fitted shape of a T, an L, a bowl or a mug covers air the
    fingers would close on, and so does a wall under a bowl's rim."""
    fitted = fitted_surface(det, spacing_m)
    points = det.points_base_m
    if points is None or len(points) < 10:
        return fitted
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    normals = estimate_normals(pts, viewpoint_base_m=viewpoint_base_m)
    keep = voxel_indices(pts, spacing_m)
    fitted_pts, fitted_nrm = fitted.points_base_m, fitted.normals_base
    if viewpoint_base_m is not None:
        from scipy.spatial import cKDTree

        seen = pts[voxel_indices(pts, 0.003)]
        real = ~seen_through(fitted_pts, seen, viewpoint_base_m)
        fitted_pts, fitted_nrm = fitted_pts[real], fitted_nrm[real]
        walls = extruded_footprint(pts, det.table_z_m, spacing_m=spacing_m)
        wall_pts, wall_nrm = walls.points_base_m, walls.normals_base
        if len(wall_pts):
            # a wall only where the fitted shape is not: the outline's walls stand up to half a cell outside the
            # true surface, so where the fitted shape already is (all round a convex footprint) they would only
            # widen the object (a standing bottle's antipodal pair ended on them, 4 mm wider and tilted)
            if len(fitted_pts):
                near = cKDTree(fitted_pts).query(wall_pts, k=1, distance_upper_bound=spacing_m)[0] <= spacing_m
                wall_pts, wall_nrm = wall_pts[~near], wall_nrm[~near]
            real = ~seen_through(wall_pts, seen, viewpoint_base_m)
            fitted_pts = np.vstack([fitted_pts, wall_pts[real]])
            fitted_nrm = np.vstack([fitted_nrm, wall_nrm[real]])
    return ObjectCloud(np.vstack([fitted_pts, pts[keep]]), np.vstack([fitted_nrm, normals[keep]]))


def box_surface(T_base_box: Mat4, size_m: Sequence[float], spacing_m: float = 0.01) -> NDArray[np.float64]:
    """Points on the six faces of a box (full sizes ``size_m`` along its axes), about ``spacing_m`` apart."""
    half = np.asarray(size_m, dtype=float) / 2
    faces = []
    for axis in range(3):
        u_ax, v_ax = [a for a in range(3) if a != axis]
        u = np.linspace(-half[u_ax], half[u_ax], max(2, math.ceil(2 * half[u_ax] / spacing_m) + 1))
        v = np.linspace(-half[v_ax], half[v_ax], max(2, math.ceil(2 * half[v_ax] / spacing_m) + 1))
        uu, vv = np.meshgrid(u, v)
        for sign in (1.0, -1.0):
            local = np.zeros((uu.size, 3))
            local[:, axis], local[:, u_ax], local[:, v_ax] = sign * half[axis], uu.ravel(), vv.ravel()
            faces.append(local)
    T = np.asarray(T_base_box, dtype=float)
    return np.asarray(np.vstack(faces) @ T[:3, :3].T + T[:3, 3], dtype=float)


def voxel_indices(points: NDArray[np.float64], voxel_m: float) -> NDArray[np.intp]:
    """One point per ``voxel_m`` cube (the first in the input's order), sorted: a thinned cloud, deterministic."""
    keys = np.floor(np.asarray(points, dtype=float) / voxel_m).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return np.sort(first)


def _side_circle(det: results.Detection) -> tuple[float, float, float] | None:
    """(x, y, radius) of the circle through the visible side of a round object (least squares, Kasa), from the
    points of its lower 60 % (a bottle's body, not its neck); None without enough points or with a circle no
    wider than the footprint (the camera sees a round object's side as an arc, its top as a smaller disc)."""
    if det.points_base_m is None:
        return None
    pts = np.asarray(det.points_base_m, dtype=float).reshape(-1, 3)
    low = pts[pts[:, 2] < det.table_z_m + 0.6 * det.size_m[2]]
    if len(low) < 20:
        return None
    A = np.column_stack([low[:, 0], low[:, 1], np.ones(len(low))])
    b = low[:, 0] ** 2 + low[:, 1] ** 2
    (a0, a1, a2), *_ = np.linalg.lstsq(A, b, rcond=None)
    cx, cy = a0 / 2, a1 / 2
    r2 = a2 + cx**2 + cy**2
    if r2 <= 0:
        return None
    r = math.sqrt(r2)
    if not max(det.size_m[0], det.size_m[1]) / 2 <= r <= 0.1:
        return None
    return float(cx), float(cy), r


def fitted_surface(det: results.Detection, spacing_m: float = 0.005) -> ObjectCloud:
    """Points and outward normals on the detection's fitted shape (sides and top), ``spacing_m`` apart: the
    gravity-aligned box, or for a round footprint an upright cylinder (fitted to the visible side's arc when the
    detection carries its points: :func:`_side_circle`)."""
    length, width, height = (float(v) for v in det.size_m)
    cx, cy, _ = (float(v) for v in det.centroid_base_m)
    z0 = det.table_z_m
    zs = z0 + np.arange(spacing_m / 2, height, spacing_m)
    if det.shape == "round":
        r = max(length, width) / 2
        circle = _side_circle(det)
        if circle is not None:
            cx, cy, r = circle
        n_around = max(12, math.ceil(2 * math.pi * r / spacing_m))
        ang = np.arange(n_around) * 2 * math.pi / n_around
        ring = np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=1)
        side = np.concatenate([np.column_stack([cx + r * ring[:, 0], cy + r * ring[:, 1], np.full(n_around, z)])
                               for z in zs])
        side_n = np.tile(ring, (len(zs), 1))
        g = np.arange(-r, r + 1e-9, spacing_m)
        gx, gy = np.meshgrid(g, g)
        keep = gx**2 + gy**2 <= r**2
        top = np.column_stack([cx + gx[keep], cy + gy[keep], np.full(int(keep.sum()), z0 + height)])
    else:
        c, s_ = math.cos(det.yaw_rad), math.sin(det.yaw_rad)
        R = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
        side_list, n_list = [], []
        for axis, half, other_half in ((0, length / 2, width / 2), (1, width / 2, length / 2)):
            u = np.arange(-other_half, other_half + 1e-9, spacing_m)
            uu, zz = np.meshgrid(u, zs)
            for sign in (1.0, -1.0):
                local = np.zeros((uu.size, 3))
                local[:, axis], local[:, 1 - axis], local[:, 2] = sign * half, uu.ravel(), zz.ravel()
                normal = np.zeros(3)
                normal[axis] = sign
                side_list.append(local)
                n_list.append(np.tile(normal, (uu.size, 1)))
        local_side = np.vstack(side_list)
        side = local_side @ R.T + [cx, cy, 0.0]
        side_n = np.vstack(n_list) @ R.T
        gx, gy = np.meshgrid(np.arange(-length / 2, length / 2 + 1e-9, spacing_m),
                             np.arange(-width / 2, width / 2 + 1e-9, spacing_m))
        local_top = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
        top = local_top @ R.T + [cx, cy, z0 + height]
    top_n = np.tile([0.0, 0.0, 1.0], (len(top), 1))
    return ObjectCloud(np.vstack([side, top]), np.vstack([side_n, top_n]))
