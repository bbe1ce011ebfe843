"""A light tracker for visual following: the target's colour blob and the depth at its pixels.

Between full perceptions (``pipeline.perceive``: plane, clusters, geometry, ~100 ms), following a known
object at the camera rate needs far less: the HSV mask of its colour, the connected component nearest to
where the target is expected, and where its top face is.

* With valid depth on the blob (the usual case: eye-to-hand, or a wrist camera beyond the D435's 0.28 m
  minimum range), the blob's pixels are back-projected into the base frame and, when the support's height
  is known (the track's), described by the pipeline's own robust footprint (``segment.object_geometry``:
  top face, quantile rectangle); otherwise the target's (x, y) is the median of the points within
  ``top_band_m`` of the blob's 90 % height quantile. The plain top band is pulled 3-4 mm towards a slanted
  camera by the upper rims of the side faces; the footprint's centre is not (measured: 1.7 mm median).
* A blob cut by the image border is no measurement (its centre would be pulled inwards).
* Without depth (a wrist camera closer than the minimum range), the blob's pixel rays are intersected with
  the plane of the target's top face, whose height the full perception gave. Side faces facing the camera
  are in the blob too and land on the camera's side, so the centre is taken from the far edge (made by the
  top face alone) minus half the footprint's extent in that direction (see ``_top_centre_from_hits``).

Everything here is camera geometry and the colour model; no simulator truth.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception import cloud as pc
from bt_grasp.perception.color import color_mask, to_hsv
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.segment import Plane, object_geometry

#: fewest blob pixels with depth for a depth measurement; fewer: the top-plane intersection is used
_MIN_DEPTH_PIXELS = 40
_TOP_QUANTILE = 0.9
#: the depth path needs this share of the blob's pixels with depth (a partly ranged blob is biased)
_MIN_DEPTH_SHARE = 0.7
#: the far edge of the top face: this quantile of the blob's extent away from the camera (not the maximum,
#: for colour-noise pixels; high enough that a square's corner is not cut off)
_FAR_EDGE_QUANTILE = 0.995


@dataclass(frozen=True)
class BlobMeasurement:
    """Where the target's top face is, from one frame (base frame, metres)."""

    xy_base_m: tuple[float, float]
    top_z_m: float
    pixel_uv: tuple[float, float]  # the blob's centroid in the image
    area_px: int
    used_depth: bool  # False: the top-plane intersection (no depth on the blob)


def _choose_component(mask: NDArray[np.uint8], expected_uv: tuple[float, float] | None, min_area_px: int
                      ) -> NDArray[np.bool_] | None:
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    candidates = [k for k in range(1, n) if stats[k, cv2.CC_STAT_AREA] >= min_area_px]
    if not candidates:
        return None
    if expected_uv is None:
        best = max(candidates, key=lambda k: stats[k, cv2.CC_STAT_AREA])
    else:
        ex = np.asarray(expected_uv, dtype=float)
        best = min(candidates, key=lambda k: float(np.linalg.norm(centroids[k] - ex)))
    return np.asarray(labels == best)


def project_to_pixel(point_base: NDArray[np.float64], T_base_camera: Mat4, frame: RGBDFrame
                     ) -> tuple[float, float] | None:
    """Where a base-frame point appears in the image; None when it is behind the camera."""
    p = np.linalg.inv(T_base_camera) @ np.array([*point_base[:3], 1.0])
    if p[2] <= 1e-3:
        return None
    intr = frame.intrinsics
    return float(intr.fx_px * p[0] / p[2] + intr.cx_px), float(intr.fy_px * p[1] / p[2] + intr.cy_px)


@dataclass(frozen=True)
class Footprint:
    """The target's footprint from the full perception: long side, narrow side (m), long side's yaw (rad)."""

    length_m: float
    width_m: float
    yaw_rad: float

    def extent_along(self, direction_rad: float) -> float:
        """The footprint's extent along a horizontal direction."""
        a = self.yaw_rad - direction_rad
        return float(abs(self.length_m * np.cos(a)) + abs(self.width_m * np.sin(a)))


def _top_centre_from_hits(hits: NDArray[np.float64], camera_xy: NDArray[np.float64], footprint: Footprint | None
                          ) -> tuple[float, float]:
    """The top face's centre from the blob's rays cut with its plane. Side faces seen from the camera's side
    land between the camera and the object, so along the direction away from the camera the far edge (which
    only the top face makes) minus half the footprint is the centre; across it, the middle of the spread."""
    median = np.median(hits[:, :2], axis=0)
    away = median - camera_xy
    if footprint is None or float(np.linalg.norm(away)) < 0.02:
        return float(median[0]), float(median[1])
    d = away / float(np.linalg.norm(away))
    n = np.array([-d[1], d[0]])
    along, across = hits[:, :2] @ d, hits[:, :2] @ n
    far = float(np.quantile(along, _FAR_EDGE_QUANTILE))
    centre_along = far - footprint.extent_along(float(np.arctan2(d[1], d[0]))) / 2
    lo, hi = np.quantile(across, (0.02, 0.98))
    c = centre_along * d + 0.5 * float(lo + hi) * n
    return float(c[0]), float(c[1])


def measure_blob(frame: RGBDFrame, T_base_camera: Mat4, color: str, config: PerceptionConfig, *,
                 top_z_hint_m: float | None, expected_base_m: NDArray[np.float64] | None = None,
                 top_band_m: float = 0.012, footprint: Footprint | None = None,
                 support_z_m: float | None = None) -> BlobMeasurement | None:
    """The target's top-face centre from its colour blob; None when no blob of the colour is in view."""
    hsv = to_hsv(frame.color)
    mask = color_mask(hsv, config.color.ranges[color], config.color)
    expected_uv = None
    if expected_base_m is not None:
        expected_uv = project_to_pixel(np.asarray(expected_base_m, dtype=float), T_base_camera, frame)
    component = _choose_component(mask, expected_uv, config.color.min_area_px)
    if component is None:
        return None
    rows, cols = np.nonzero(component)
    h, w = component.shape
    if rows.min() == 0 or cols.min() == 0 or rows.max() == h - 1 or cols.max() == w - 1:
        return None  # cut by the image border: its centre would be pulled inwards
    uv = (float(cols.mean()), float(rows.mean()))
    depth = np.asarray(frame.depth_m, dtype=np.float32)
    with_depth = component & pc.valid_depth_mask(depth, config.cloud) & (depth > 0)
    T = np.asarray(T_base_camera, dtype=float)
    if int(with_depth.sum()) >= max(_MIN_DEPTH_PIXELS, _MIN_DEPTH_SHARE * len(rows)):
        pts = pc.to_base(pc.depth_to_cloud(depth, frame.intrinsics, with_depth), T).points
        if support_z_m is not None:  # the pipeline's robust footprint on the support plane (side faces ignored)
            geo = object_geometry(pts, Plane(np.array([0.0, 0.0, 1.0]), -float(support_z_m)), config.segmentation)
            return BlobMeasurement((float(geo.centre_base_m[0]), float(geo.centre_base_m[1])),
                                   float(support_z_m + geo.height_m), uv, len(rows), True)
        level = float(np.quantile(pts[:, 2], _TOP_QUANTILE))
        top = pts[np.abs(pts[:, 2] - level) < top_band_m]
        if len(top) >= 10:
            return BlobMeasurement((float(np.median(top[:, 0])), float(np.median(top[:, 1]))),
                                   float(np.median(top[:, 2])), uv, len(rows), True)
    if top_z_hint_m is None:
        return None
    intr = frame.intrinsics
    rays_cam = np.stack([(cols - intr.cx_px) / intr.fx_px, (rows - intr.cy_px) / intr.fy_px,
                         np.ones(len(rows))], axis=1)
    rays = rays_cam @ T[:3, :3].T
    origin = T[:3, 3]
    ok = rays[:, 2] < -1e-6  # rays going down towards the plane
    if ok.sum() < 10:
        return None
    s = (top_z_hint_m - origin[2]) / rays[ok, 2]
    hits = origin[None, :] + s[:, None] * rays[ok]
    return BlobMeasurement(_top_centre_from_hits(hits, origin[:2], footprint), float(top_z_hint_m), uv, len(rows),
                           False)
