"""The learned detector joined with depth: a detection's oriented box selects the depth points inside it (the
table plane already removed), the object cluster it covers becomes the object, with the box's class and score.

``join_boxes`` takes the geometric pipeline's result for the same frame (its table plane and every object
cluster, with its points in the base frame) and the network's boxes (``bt_grasp.detector.obb.OrientedDetection``,
in the colour image's pixels). Each object's points are projected back into the image through the calibration
(``T_base_camera``) and the intrinsics; boxes are taken best score first:

* the box's object is the cluster with the most not-yet-claimed points inside the box (fewer than the
  segmentation's ``min_cluster_points``: no object under the box, the box is dropped);
* when at least :data:`WHOLE_FRACTION` of that cluster lies inside the box, and no other sure box of the frame
  lying mostly elsewhere (most of the cluster's points it covers are outside this box: not a second box over the
  same object) covers an object's worth (``min_cluster_points``) of the cluster's points outside this one, the
  whole cluster is the object (the network's box is a little tight or loose; the depth is what decides the
  object's extent); otherwise the cluster holds more than this object (touching objects clustered together: a
  plate's box, a square around a disc, also covers the corner of a small box pushed against its rim) and only
  its points inside the box are described, as the geometric pipeline describes a cluster;
* boxes at or above :data:`SURE_SCORE` (the decoder's usual threshold) are joined first, best score first; then
  boxes down to :data:`TENTATIVE_SCORE`, which may only name a whole cluster no surer box touched and which lies
  at least :data:`TENTATIVE_COVER` inside them (a weak box is often short of the object's ends). A network's
  score is weak evidence on its own (a box over bare table, a second guess over a named object), but a box that
  frames one unnamed object the depth found is two pieces of evidence agreeing: a black pen the network scores
  0.2 is still the pen when a tree asks for one. Such an object keeps its low ``class_score``, so a surer one of
  the same class always ranks first;
* the box's long axis, carried to the table through the camera's rays, decides the object's ``yaw_rad``, the
  axis the grasp closes across (as the systems that grasp from YOLO-OBB boxes do): within
  :data:`AGREE_RAD` of the footprint's own long axis, the footprint's axis (measured on the points, it is the
  finer of the two: a box drawn around an object seen obliquely leans a degree or so); further off, the box's
  axis, with the footprint's length measured along it and its width across it. Round objects, near-square
  boxes and boxes whose long axis is the short one of the points keep the geometry's own yaw.

Clusters no box claimed stay in ``others`` without a class (every object seen matters for clearance). Nothing here
reads the simulator: the only pose is ``T_base_camera``, from the hand-eye calibration.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import CameraIntrinsics, RGBDFrame
from bt_grasp.perception import cloud as pc
from bt_grasp.perception.color import to_hsv
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.pipeline import _describe
from bt_grasp.perception.results import Detection, OrientedBox, PerceptionResult, PerceptionStatus
from bt_grasp.perception.segment import Plane, gravity_axes

#: a box covering at least this fraction of a cluster's points takes the whole cluster
WHOLE_FRACTION = 0.8
#: boxes at or above this score name what they cover (Ultralytics' and ``bt_grasp.detector.obb``'s ``conf``)
SURE_SCORE = 0.25
#: boxes from this score up to SURE_SCORE name only a whole object no surer box touched (see the module's text);
#: the learned detector is decoded down to this score
TENTATIVE_SCORE = 0.10
#: a box under SURE_SCORE names a cluster no surer box touched when it covers at least this fraction of it
TENTATIVE_COVER = 0.5
#: a box this much longer than wide (in the image) has a long axis worth following
MIN_ASPECT = 1.3
#: a box's long axis this close to the footprint's own long axis agrees with it (the footprint's is kept)
AGREE_RAD = math.radians(15.0)
#: the footprint's extent along and across a box's axis: between these quantiles of the points (a footprint
#: turned against that axis has few points in its corners: the geometry's 1 % / 99 % would cut them by ~1 cm)
EXTENT_QUANTILES = (0.002, 0.998)


class BoxLike(Protocol):
    """What the join reads of a detection (``bt_grasp.detector.obb.OrientedDetection``)."""

    @property
    def width_px(self) -> float: ...
    @property
    def height_px(self) -> float: ...
    @property
    def cx_px(self) -> float: ...
    @property
    def cy_px(self) -> float: ...
    @property
    def class_name(self) -> str: ...
    @property
    def score(self) -> float: ...
    @property
    def long_axis_rad(self) -> float: ...

    def corners_px(self) -> NDArray[np.float64]: ...


def project(points_base: NDArray[np.float64], T_base_camera: Mat4, intr: CameraIntrinsics) -> NDArray[np.float64]:
    """Base-frame points (N, 3) -> pixel coordinates (N, 2) (u, v) in the colour image; behind the camera: NaN."""
    T_camera_base = np.linalg.inv(np.asarray(T_base_camera, dtype=float))
    cam = points_base @ T_camera_base[:3, :3].T + T_camera_base[:3, 3]
    z = np.where(cam[:, 2] > 1e-6, cam[:, 2], np.nan)
    return np.stack([intr.fx_px * cam[:, 0] / z + intr.cx_px, intr.fy_px * cam[:, 1] / z + intr.cy_px], axis=1)


def box_mask(box: BoxLike, width_px: int, height_px: int) -> NDArray[np.bool_]:
    """The pixels whose centres the oriented box covers (H, W)."""
    mask = np.zeros((height_px, width_px), dtype=np.uint8)
    corners = np.round(box.corners_px() * 16).astype(np.int32)  # 4 fractional bits: sub-pixel corners
    cv2.fillPoly(mask, [corners], 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


def _inside(pixels: NDArray[np.float64], mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    h, w = mask.shape
    ok = np.all(np.isfinite(pixels), axis=1)
    uv = np.zeros((len(pixels), 2), dtype=np.intp)
    uv[ok] = np.round(pixels[ok]).astype(np.intp)
    ok &= (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
    out = np.zeros(len(pixels), dtype=bool)
    out[ok] = mask[uv[ok, 1], uv[ok, 0]]
    return out


def _ray_on_height(uv: NDArray[np.float64], T_base_camera: Mat4, intr: CameraIntrinsics,
                   z_m: float) -> NDArray[np.float64] | None:
    """Where the camera rays through pixels ``uv`` (N, 2) cross the horizontal plane base z = ``z_m``."""
    T = np.asarray(T_base_camera, dtype=float)
    rays = np.stack([(uv[:, 0] - intr.cx_px) / intr.fx_px, (uv[:, 1] - intr.cy_px) / intr.fy_px,
                     np.ones(len(uv))], axis=1) @ T[:3, :3].T
    if np.any(np.abs(rays[:, 2]) < 1e-9):
        return None
    t = (z_m - T[2, 3]) / rays[:, 2]
    if np.any(t <= 0):
        return None
    return np.asarray(T[:3, 3] + t[:, None] * rays, dtype=np.float64)


def long_axis_yaw(box: BoxLike, T_base_camera: Mat4, intr: CameraIntrinsics, z_m: float) -> float | None:
    """The box's long axis as a yaw about base +z in (-pi/2, pi/2], carried from the image to the horizontal
    plane at ``z_m`` (the object's mid-height) through the camera's rays; None for a near-square box."""
    long_px, short_px = max(box.width_px, box.height_px), min(box.width_px, box.height_px)
    if long_px < MIN_ASPECT * max(short_px, 1e-9):
        return None
    a = box.long_axis_rad
    half = long_px / 2 * np.array([math.cos(a), math.sin(a)])
    centre = np.array([box.cx_px, box.cy_px])
    ends = _ray_on_height(np.stack([centre - half, centre + half]), T_base_camera, intr, z_m)
    if ends is None:
        return None
    d = ends[1] - ends[0]
    yaw = math.atan2(float(d[1]), float(d[0]))
    yaw = (yaw + math.pi / 2) % math.pi - math.pi / 2
    return yaw + math.pi if yaw <= -math.pi / 2 + 1e-12 else yaw


def orient_along(det: Detection, yaw_rad: float, plane: Plane) -> Detection:
    """``det`` with its footprint measured along ``yaw_rad`` (length) and across it (width): yaw, size,
    footprint, centre and gravity-aligned box. Unchanged when its points are not longer along that axis than
    across it (the box and the depth disagree) or it has no points."""
    if det.points_base_m is None or len(det.points_base_m) < 3:
        return det
    origin, e1, e2 = plane.basis()
    rel = np.asarray(det.points_base_m, dtype=float) - origin
    uv = np.stack([rel @ e1, rel @ e2], axis=1)
    axis = np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    angle = math.atan2(float(axis @ e2), float(axis @ e1))
    c, s = math.cos(angle), math.sin(angle)
    a0, a1 = (float(v) for v in np.quantile(c * uv[:, 0] + s * uv[:, 1], EXTENT_QUANTILES))
    b0, b1 = (float(v) for v in np.quantile(-s * uv[:, 0] + c * uv[:, 1], EXTENT_QUANTILES))
    length, width = a1 - a0, b1 - b0
    if length < width:
        return det
    axis_a, axis_b = c * e1 + s * e2, -s * e1 + c * e2
    foot = origin + (a0 + a1) / 2 * axis_a + (b0 + b1) / 2 * axis_b
    height = det.size_m[2]
    centre = foot + plane.normal * (height / 2)
    corners = [foot + sa * length / 2 * axis_a + sb * width / 2 * axis_b
               for sa, sb in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    axes = gravity_axes(plane, yaw_rad)
    centre_t = (float(centre[0]), float(centre[1]), float(centre[2]))
    size = (float(length), float(width), float(height))
    rows = tuple((float(r[0]), float(r[1]), float(r[2])) for r in axes)
    return replace(
        det, yaw_rad=float(yaw_rad), size_m=size, centroid_base_m=centre_t,
        footprint_base_m=tuple((float(p[0]), float(p[1])) for p in corners),
        obb=OrientedBox(centre_t, rows, size),  # type: ignore[arg-type]
    )


def _axis_gap(a_rad: float, b_rad: float) -> float:
    """The angle between two undirected axes, in [0, pi/2]."""
    d = abs(a_rad - b_rad) % math.pi
    return min(d, math.pi - d)


def _another_box_names_the_rest(covers: list[list[NDArray[np.bool_]]], sure: list[bool], i: int, k: int,
                                min_points: int) -> bool:
    """Whether a sure box other than the ``i``-th covers at least ``min_points`` of cluster ``k``'s points
    outside the ``i``-th box, and those are most of the cluster's points it covers: a box of another object, not
    a second box over the same one (``covers[box][cluster]``: which of the cluster's points the box covers)."""
    outside = ~covers[i][k]
    for j, c in enumerate(covers):
        if j == i or not sure[j]:
            continue
        beyond = int((c[k] & outside).sum())
        if beyond >= min_points and 2 * beyond > int(c[k].sum()):
            return True
    return False


def _plane(result: PerceptionResult) -> Plane | None:
    if result.table_plane_base is None:
        return None
    a, b, c, d = result.table_plane_base
    return Plane(np.array([a, b, c], dtype=float), float(d))


def join_boxes(
    result: PerceptionResult, boxes: Sequence[BoxLike], frame: RGBDFrame, T_base_camera: Mat4,
    config: PerceptionConfig | None = None, color: str | None = None,
) -> PerceptionResult:
    """The geometric ``result`` of ``frame`` with each box joined to the object it covers (see the module's
    text): ``detections`` are the objects a box named, best class score first (with ``color``: only objects of
    that colour, by label or dominant colour); ``others`` every object seen, those no box named without a class.
    A result with no object clusters (no depth, no table, an empty table) is returned as it is."""
    config = config or PerceptionConfig()
    plane = _plane(result)
    objects = [d for d in result.others if d.points_base_m is not None]
    if plane is None or not objects:
        return result
    intr = frame.intrinsics
    pixels = [project(np.asarray(d.points_base_m, dtype=float), T_base_camera, intr) for d in objects]
    claimed = [np.zeros(len(p), dtype=bool) for p in pixels]
    seg = config.segmentation
    rgb = np.asarray(frame.color, dtype=np.uint8)[..., :3]
    hsv = to_hsv(rgb)
    named: list[Detection] = []
    whole_taken: set[int] = set()
    ordered = sorted((b for b in boxes if b.score >= TENTATIVE_SCORE), key=lambda b: -b.score)
    covers = [[_inside(p, box_mask(b, intr.width_px, intr.height_px)) for p in pixels] for b in ordered]
    sure_boxes = [b.score >= SURE_SCORE for b in ordered]
    for i, box in enumerate(ordered):
        inside = [c & ~taken for c, taken in zip(covers[i], claimed, strict=True)]
        counts = [int(c.sum()) for c in inside]
        k = int(np.argmax(counts))
        if counts[k] < seg.min_cluster_points:
            continue  # no object under this box (or only points another box already took)
        det = objects[k]
        sure = sure_boxes[i]
        if sure:
            whole = (k not in whole_taken and not claimed[k].any() and counts[k] >= WHOLE_FRACTION * len(pixels[k])
                     and not _another_box_names_the_rest(covers, sure_boxes, i, k, seg.min_cluster_points))
        else:  # a tentative box names a whole object no surer box touched, or nothing
            if k in whole_taken or claimed[k].any() or counts[k] < TENTATIVE_COVER * len(pixels[k]):
                continue
            whole = True
        if whole:
            claimed[k][:] = True
            whole_taken.add(k)
            note = f"named by a {box.class_name} box under the sure score ({box.score:.2f})"
            joined: Detection | None = det if sure else replace(
                det, cluster_note="; ".join(n for n in (det.cluster_note, note) if n))
        else:
            claimed[k] |= inside[k]
            part = pc.PixelCloud(np.asarray(det.points_base_m, dtype=float)[inside[k]],
                                 np.round(pixels[k][inside[k]]).astype(np.int32))
            joined = _describe(part, plane, rgb, hsv, None, config, seg,
                               cluster_note=f"cut out of a cluster by a {box.class_name} box")
        if joined is None:
            continue
        yaw = long_axis_yaw(box, T_base_camera, intr, joined.centroid_base_m[2]) if joined.shape != "round" else None
        if yaw is not None and _axis_gap(yaw, joined.yaw_rad) > AGREE_RAD:
            joined = orient_along(joined, yaw, plane)
        named.append(replace(joined, class_name=box.class_name, class_score=float(box.score)))
    rest = [d for k, d in enumerate(objects) if not claimed[k].any()]
    rest += [d for d in result.others if d.points_base_m is None]
    others = (*named, *rest)
    ranked = [d for d in named if not color or color in (d.label, d.color_name)]
    ranked.sort(key=lambda d: (-d.class_score, d.centroid_base_m))
    timings = dict(result.timings_ms)
    if not ranked:
        what = f"{len(boxes)} box(es)" + (f", none of a {color} object" if color and named else "")
        message = f"{len(objects)} object(s) on the table; the detector named none of them ({what})"
        return replace(result, status=PerceptionStatus.NO_MATCH, detections=(), others=others, message=message,
                       timings_ms=timings)
    best = ranked[0]
    message = (f"{len(others)} object(s), {len(named)} named; best: {best.class_name} ({best.class_score:.2f}) at "
               + ", ".join(f"{v:.3f}" for v in best.centroid_base_m))
    return replace(result, status=PerceptionStatus.OK, detections=tuple(ranked), others=others, message=message,
                   timings_ms=timings)
