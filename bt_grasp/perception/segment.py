"""Table plane (RANSAC), object clusters (DBSCAN) and per-object geometry (footprint, yaw, height).

Object geometry, for objects standing on the table and seen from above at a slant:

* height = median height above the plane of the top face (the points near the highest level);
* footprint = the robust minimum-area rectangle of the top-face points projected on the plane: the angle
  minimising the area spanned between the 1 % and 99 % quantiles along the rectangle's two axes. Quantiles
  make the centre insensitive to single noisy points; side-face points near the top lie on the footprint's
  edge, so including them does not move the centre;
* centre = the footprint centre, lifted half the height above the plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from bt_grasp.perception.cloud import PixelCloud
from bt_grasp.perception.config import SegmentationSettings

Vec = NDArray[np.float64]

_ANGLES_COARSE = np.deg2rad(np.arange(0.0, 90.0, 2.0))
_QUANTILES = (0.01, 0.99)
#: a footprint whose quantile-box area varies less than this over all angles has no preferred yaw
#: (measured: cylinder 0.07, square box 0.55+)
_ROUND_SPREAD = 0.2


@dataclass(frozen=True)
class Plane:
    """Points p with normal . p + offset = 0; ``normal`` is unit length and points up (base +z side)."""

    normal: Vec
    offset: float

    def height(self, points: NDArray[np.float64]) -> Vec:
        return points @ self.normal + self.offset

    def basis(self) -> tuple[Vec, Vec, Vec]:
        """(origin, e1, e2): the foot of the base origin on the plane and two in-plane unit axes, e1 ~ base x."""
        n = self.normal
        origin = -self.offset * n
        e1 = np.array([1.0, 0.0, 0.0]) - n[0] * n
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        return origin, e1, e2

    def as_tuple(self) -> tuple[float, float, float, float]:
        return (float(self.normal[0]), float(self.normal[1]), float(self.normal[2]), float(self.offset))


def _ransac_plane(points: NDArray[np.float64], distance_m: float, iterations: int, seed: int
                  ) -> tuple[Vec, float, NDArray[np.intp]] | None:
    """The plane through three sampled points with the most inliers; samples drawn from ``seed``'s stream.

    Open3D's ``segment_plane`` samples in OpenMP threads and gives other planes under load even with a fixed
    seed (isl-org/Open3D#7270): a run must not depend on thread scheduling, so this sampling is sequential
    and seeded, and the inlier counting vectorised.
    """
    rng = np.random.default_rng(seed)
    triplets = rng.integers(0, len(points), size=(iterations, 3))
    p0, p1, p2 = points[triplets[:, 0]], points[triplets[:, 1]], points[triplets[:, 2]]
    normals = np.cross(p1 - p0, p2 - p0)
    norms = np.linalg.norm(normals, axis=1)
    keep = norms > 1e-12  # repeated or collinear samples define no plane
    if not np.any(keep):
        return None
    normals = normals[keep] / norms[keep, None]
    offsets = -np.einsum("ij,ij->i", normals, p0[keep])
    counts = np.zeros(len(normals), dtype=np.int64)
    # |points . n + offset| < distance for 32 planes at a time, in two buffers reused in place: the same
    # operations on the same values as fresh temporaries, without page-faulting ~8 MB of new memory per step
    # (3x faster on ~30k points). Each view is C-contiguous, so the product goes through BLAS as before.
    dist_buf = np.empty(len(points) * 32)
    near_buf = np.empty(len(points) * 32, dtype=bool)
    for start in range(0, len(normals), 32):
        stop = min(start + 32, len(normals))
        dist = dist_buf[:len(points) * (stop - start)].reshape(len(points), stop - start)
        near = near_buf[:dist.size].reshape(dist.shape)
        np.matmul(points, normals[start:stop].T, out=dist)
        np.add(dist, offsets[start:stop], out=dist)
        np.abs(dist, out=dist)
        np.less(dist, distance_m, out=near)
        counts[start:stop] = np.count_nonzero(near, axis=0)
    best = int(np.argmax(counts))  # the first of equals: deterministic
    inliers = np.nonzero(np.abs(points @ normals[best] + offsets[best]) < distance_m)[0]
    return normals[best], float(offsets[best]), inliers


def fit_table_plane(pcd: o3d.geometry.PointCloud, settings: SegmentationSettings, seed: int = 0) -> Plane | None:
    """RANSAC plane, refined by least squares on its inliers; None when no near-horizontal plane exists."""
    if len(pcd.points) < 50:
        return None
    points = np.asarray(pcd.points)
    found = _ransac_plane(points, settings.plane_distance_m, settings.plane_iterations, seed)
    if found is None:
        return None
    normal, offset, inliers = found
    if len(inliers) < 50:
        return None
    if normal[2] < 0:
        normal, offset = -normal, -offset
    if np.degrees(np.arccos(np.clip(normal[2], -1.0, 1.0))) > settings.plane_max_tilt_deg:
        return None
    pts = points[inliers]
    centre = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - centre, full_matrices=False)
    refined = vt[2] if vt[2] @ normal > 0 else -vt[2]
    return Plane(refined, float(-refined @ centre))


def cluster(points: NDArray[np.float64], settings: SegmentationSettings) -> list[NDArray[np.intp]]:
    """DBSCAN clusters of the off-plane points (indices), noise dropped, size-filtered, largest first."""
    if len(points) < settings.min_cluster_points:
        return []
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    labels = np.asarray(pcd.cluster_dbscan(settings.cluster_eps_m, settings.cluster_min_points, False))
    out = []
    for label in range(int(labels.max(initial=-1)) + 1):
        idx = np.nonzero(labels == label)[0]
        if len(idx) < settings.min_cluster_points:
            continue
        extent = points[idx].max(axis=0) - points[idx].min(axis=0)
        if float(np.max(extent)) > settings.max_cluster_extent_m:
            continue
        out.append(idx)
    out.sort(key=len, reverse=True)
    return out


def assign_full_resolution(
    full: PixelCloud, heights: Vec, sparse_points: NDArray[np.float64], sparse_labels: NDArray[np.intp],
    radius_m: float, min_height_m: float,
) -> list[PixelCloud]:
    """Give every full-resolution off-plane point the cluster label of its nearest clustered sparse point."""
    n_clusters = int(sparse_labels.max(initial=-1)) + 1
    if n_clusters == 0:
        return []
    above = np.nonzero(heights > min_height_m)[0]
    tree = cKDTree(sparse_points)
    dist, nearest = tree.query(full.points[above], k=1, distance_upper_bound=radius_m)
    found = np.isfinite(dist)
    labels = np.full(len(above), -1, dtype=np.intp)
    labels[found] = sparse_labels[nearest[found]]
    return [full.select(above[labels == k]) for k in range(n_clusters)]


@dataclass(frozen=True)
class ObjectGeometry:
    centre_base_m: Vec
    length_m: float
    width_m: float
    height_m: float
    yaw_rad: float  # direction of the long side about base +z, in (-pi/2, pi/2]
    round: bool  # the footprint has no preferred direction (a cylinder or a sphere seen from above)
    footprint_base_m: NDArray[np.float64]  # (4, 2) rectangle corners, x y
    principal_axes: NDArray[np.float64]  # (3, 3) PCA axes as rows, largest variance first
    top_point_count: int


def _quantile_extents(uv: NDArray[np.float64], angles: Vec) -> tuple[Vec, Vec, Vec, Vec]:
    """For each angle: low and high quantiles of the points along the rotated axes a and b."""
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    a = c * uv[None, :, 0] + s * uv[None, :, 1]
    b = -s * uv[None, :, 0] + c * uv[None, :, 1]
    qa = np.quantile(a, _QUANTILES, axis=1)
    qb = np.quantile(b, _QUANTILES, axis=1)
    return qa[0], qa[1], qb[0], qb[1]


def _best_angle(uv: NDArray[np.float64]) -> tuple[float, float]:
    """The rectangle angle (0..pi/2) minimising the quantile box area, and the area spread (max/min - 1)."""
    a0, a1, b0, b1 = _quantile_extents(uv, _ANGLES_COARSE)
    area = (a1 - a0) * (b1 - b0)
    k = int(np.argmin(area))
    spread = float(area.max() / max(area.min(), 1e-12) - 1.0)
    best = float(_ANGLES_COARSE[k])
    for step in (np.deg2rad(0.5), np.deg2rad(0.1)):
        fine = best + step * np.arange(-4, 5)
        a0, a1, b0, b1 = _quantile_extents(uv, fine)
        best = float(fine[int(np.argmin((a1 - a0) * (b1 - b0)))])
    return best, spread


def object_geometry(points: NDArray[np.float64], plane: Plane, settings: SegmentationSettings) -> ObjectGeometry:
    """Footprint, yaw, height and centre of one object's points (base frame)."""
    h = plane.height(points)
    level = float(np.quantile(h, 0.97))
    for _ in range(2):
        band = np.abs(h - level) < settings.top_band_m
        if band.sum() < 5:
            break
        level = float(np.median(h[band]))
    top = np.abs(h - level) < settings.top_band_m
    if top.sum() < 20:  # no flat top (a sphere): use everything
        top = np.ones(len(points), dtype=bool)
    height = max(level, 1e-3)
    origin, e1, e2 = plane.basis()
    rel = points[top] - origin
    uv = np.stack([rel @ e1, rel @ e2], axis=1)
    angle, spread = _best_angle(uv)
    a0, a1, b0, b1 = (float(v[0]) for v in _quantile_extents(uv, np.array([angle])))
    extent_a, extent_b = a1 - a0, b1 - b0
    ca, cb = (a0 + a1) / 2, (b0 + b1) / 2
    c, s = np.cos(angle), np.sin(angle)
    axis_a = c * e1 + s * e2
    axis_b = -s * e1 + c * e2
    long_axis = axis_a if extent_a >= extent_b else axis_b
    length, width = max(extent_a, extent_b), min(extent_a, extent_b)
    foot_centre = origin + ca * axis_a + cb * axis_b
    centre = foot_centre + plane.normal * (height / 2)
    yaw = float(np.arctan2(long_axis[1], long_axis[0]))
    yaw = (yaw + np.pi / 2) % np.pi - np.pi / 2
    if yaw <= -np.pi / 2 + 1e-12:
        yaw += np.pi
    corners = np.array(
        [foot_centre + sa * extent_a / 2 * axis_a + sb * extent_b / 2 * axis_b for sa, sb in
         ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    )[:, :2]
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    return ObjectGeometry(
        centre_base_m=centre,
        length_m=float(length),
        width_m=float(width),
        height_m=float(height),
        yaw_rad=yaw,
        round=spread < _ROUND_SPREAD,
        footprint_base_m=corners,
        principal_axes=vt,
        top_point_count=int(top.sum()),
    )


#: robust extent quantiles of the PCA box (a few stray points do not grow it)
_PCA_QUANTILES = (0.005, 0.995)
#: cell side of the top-view occupancy grid used for the shape class, m
_FILL_CELL_M = 0.005
#: one side at least this many times the next makes an object elongated
_ELONGATED_RATIO = 2.5
#: an object at most this fraction of its footprint's narrow side high (and under _FLAT_MAX_M) is flat
_FLAT_RATIO = 0.35
_FLAT_MAX_M = 0.03
#: top-view fill of the footprint rectangle above which a footprint is a full rectangle
_FULL_FILL = 0.75


def _unit_sign(v: Vec) -> Vec:
    """``v`` with a deterministic sign: its first component of magnitude > 1e-6 (x, then y, then z) positive."""
    for c in v:
        if abs(c) > 1e-6:
            return v if c > 0 else -v
    return v


def pca_box(points: NDArray[np.float64]) -> tuple[Vec, NDArray[np.float64], Vec]:
    """Centre, axes (3, 3) as rows (a right-handed frame, largest spread first) and extents of the points'
    box in their PCA frame, extents between the 0.5 % and 99.5 % quantiles along each axis."""
    mean = points.mean(axis=0)
    centred = points - mean
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    x, y = _unit_sign(vt[0]), _unit_sign(vt[1])
    axes = np.stack([x, y, np.cross(x, y)])
    proj = centred @ axes.T
    lo, hi = np.quantile(proj, _PCA_QUANTILES, axis=0)
    centre = mean + ((lo + hi) / 2) @ axes
    return centre, axes, hi - lo


def gravity_axes(plane: Plane, yaw_rad: float) -> NDArray[np.float64]:
    """Rows x, y, z of the gravity-aligned box: z = the table normal, x = the yaw direction in the plane."""
    z = plane.normal
    x = np.array([np.cos(yaw_rad), np.sin(yaw_rad), 0.0])
    x = x - (x @ z) * z
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def footprint_fill(points: NDArray[np.float64], plane: Plane, geo: ObjectGeometry) -> tuple[float, float]:
    """How much of the object's top-view rectangle (all its points projected on the table, in the footprint's
    axes, between the 1 % and 99 % quantiles) it covers seen from above: (all points, points within 1 cm of
    its top), each the share of the rectangle's 5 mm cells holding at least one point."""
    axes = gravity_axes(plane, geo.yaw_rad)
    rel = points - geo.centre_base_m
    a, b = rel @ axes[0], rel @ axes[1]
    (a0, b0), (a1, b1) = np.quantile(np.stack([a, b], axis=1), _QUANTILES, axis=0)
    na = max(1, round(float(a1 - a0) / _FILL_CELL_M))
    nb = max(1, round(float(b1 - b0) / _FILL_CELL_M))
    ia = np.floor((a - a0) / max(a1 - a0, 1e-6) * na).astype(np.int64)
    ib = np.floor((b - b0) / max(b1 - b0, 1e-6) * nb).astype(np.int64)
    inside = (ia >= 0) & (ia < na) & (ib >= 0) & (ib < nb)
    top = inside & (plane.height(points) > geo.height_m - 0.01)

    def share(mask: NDArray[np.bool_]) -> float:
        return float(len(np.unique(ia[mask] * nb + ib[mask]))) / float(na * nb)

    return share(inside), share(top)


def shape_class_of(geo: ObjectGeometry, fill_all: float, fill_top: float) -> str:
    """The shape class's value (see ``results.ShapeClass``) from the gravity box and the top-view fill."""
    sides = sorted((geo.length_m, geo.width_m, geo.height_m), reverse=True)
    if geo.height_m <= min(_FLAT_RATIO * geo.width_m, _FLAT_MAX_M):
        return "flat"
    if geo.round:
        return "cylinder-like"
    if sides[0] >= _ELONGATED_RATIO * sides[1]:
        return "elongated"
    if fill_all >= _FULL_FILL:
        return "box-like" if fill_top >= _FULL_FILL else "cylinder-like"
    return "other"
