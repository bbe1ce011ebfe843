"""``perceive``: one RGB-D frame + the camera's pose in the robot base frame -> objects on the table.

Stages (each timed into ``PerceptionResult.timings_ms``): back-projection, transform to the base frame and
region-of-interest crop, voxel downsampling, statistical outlier removal, RANSAC table plane, DBSCAN
clustering of what stands on the plane, touching objects cut apart at height steps (``split.py``),
per-object geometry from the full-resolution points, and colour
evidence (HSV mask + morphology + minimum-area rectangles) matched to the clusters through the pixels their
points came from. Nothing here reads simulator ground truth: the only pose used is ``T_base_camera``, from
the hand-eye calibration (for an eye-in-hand camera, the caller composes it with the tool pose at capture).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception import cloud as pc
from bt_grasp.perception import noise_adapt
from bt_grasp.perception.color import blobs, classify, color_mask, dominant_color, to_hsv
from bt_grasp.perception.config import PerceptionConfig, SegmentationSettings
from bt_grasp.perception.results import Detection, OrientedBox, PerceptionResult, PerceptionStatus, ShapeClass
from bt_grasp.perception.segment import (
    Plane,
    assign_full_resolution,
    cluster,
    fit_table_plane,
    footprint_fill,
    gravity_axes,
    object_geometry,
    pca_box,
    shape_class_of,
)
from bt_grasp.perception.split import split_touching

log = logging.getLogger(__name__)

#: points on an object at which the detection confidence saturates
_FULL_CONFIDENCE_POINTS = 150


class _Timer:
    def __init__(self) -> None:
        self.ms: dict[str, float] = {}
        self._start = time.perf_counter()

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.ms[name] = self.ms.get(name, 0.0) + (time.perf_counter() - t0) * 1e3

    def total(self) -> dict[str, float]:
        out = dict(self.ms)
        out["total"] = (time.perf_counter() - self._start) * 1e3
        return out


def _status(status: PerceptionStatus, timer: _Timer, message: str, **kw: object) -> PerceptionResult:
    log.info("perception: %s (%s)", status.value, message)
    return PerceptionResult(status=status, timings_ms=timer.total(), message=message, **kw)  # type: ignore[arg-type]


def _check_inputs(frame: RGBDFrame | None, T_base_camera: Mat4) -> str | None:
    if frame is None:
        return "no frame arrived from the camera"
    depth = np.asarray(frame.depth_m)
    if depth.ndim != 2 or depth.size == 0:
        return f"the depth image is empty (shape {depth.shape})"
    T = np.asarray(T_base_camera, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ValueError(f"T_base_camera must be a finite 4x4 transform, got shape {T.shape}")
    return None


def perceive(
    frame: RGBDFrame | None,
    T_base_camera: Mat4,
    config: PerceptionConfig | None = None,
    color: str | None = None,
    *,
    size_hint_m: tuple[float, float, float] | None = None,
    seed: int = 0,
) -> PerceptionResult:
    """Find the objects standing on the table in one frame; ranked for the request (colour or size hint).

    ``seed``: the table plane's RANSAC samples (a run passes its ``PERCEPTION`` stream: ``bt_grasp.seeds``).

    ``T_base_camera`` maps points from the camera's optical frame (OpenCV axes) into the robot base frame.
    ``color`` names a colour of ``config.color.ranges``; None ranks by size similarity to ``size_hint_m``
    (length, width, height) when given, else by graspable size (narrow side) and point support.
    Expected failures are statuses with a message, never exceptions; an unknown colour name is a
    ValueError (a programming or configuration error).
    """
    config = config or PerceptionConfig()
    timer = _Timer()
    if color is not None and color not in config.color.ranges:
        raise ValueError(f"unknown colour {color!r}; known: {', '.join(config.color.ranges)}")
    problem = _check_inputs(frame, T_base_camera)
    if problem is not None or frame is None:
        return _status(PerceptionStatus.NO_DEPTH, timer, problem or "no frame")
    depth = np.asarray(frame.depth_m, dtype=np.float32)
    T_base_camera = np.asarray(T_base_camera, dtype=float)
    seg = config.segmentation
    with timer.stage("cloud"):
        valid = pc.valid_depth_mask(depth, config.cloud)
        n_valid = int(valid.sum())
        if n_valid == 0:
            return _status(PerceptionStatus.NO_DEPTH, timer, "no valid depth reading in the frame")
        window = pc.roi_pixel_window(config.roi, T_base_camera, frame.intrinsics)
        if window is not None:
            u0, v0, u1, v1 = window
            in_window = np.zeros_like(valid)
            in_window[v0:v1, u0:u1] = True
            valid &= in_window
    with timer.stage("noise"):
        noise = noise_adapt.measure(depth, valid, config.noise)
        if noise.filter_radius_px:
            depth = noise_adapt.denoise_depth(depth, valid, noise.filter_radius_px, noise.k_per_m,
                                              config.noise.gate_sigmas)
            valid &= depth > 0
    with timer.stage("cloud"):
        cam = pc.depth_to_cloud(depth, frame.intrinsics, valid)
    with timer.stage("roi"):
        roi = pc.crop_roi(pc.to_base(cam, T_base_camera), config.roi)
    if len(roi) < 100:
        return _status(PerceptionStatus.NO_POINTS, timer,
                       f"{len(roi)} of {n_valid} valid points lie in the region of interest")
    with timer.stage("voxel"):
        sparse = pc.downsample(roi.points, config.cloud.voxel_m)
    height_sigma = 0.0
    with timer.stage("plane"):
        seg = noise_adapt.adapt_segmentation(seg, noise.sigma_after_m, config.noise)
        plane = fit_table_plane(sparse, seg, seed)
        if plane is not None:
            sparse_h = plane.height(np.asarray(sparse.points))
            height_sigma = noise_adapt.height_spread_m(sparse_h[np.abs(sparse_h) < seg.plane_distance_m])
            seg = noise_adapt.adapt_segmentation(seg, height_sigma, config.noise)
    if plane is None:
        return _status(PerceptionStatus.NO_POINTS, timer, "no near-horizontal table plane in the region of interest",
                       noise=noise)
    with timer.stage("outliers"):
        sparse_pts = np.asarray(sparse.points)
        off_plane = pc.remove_outliers(pc.to_o3d(sparse_pts[plane.height(sparse_pts) > seg.min_height_m]),
                                       config.cloud)
        off_plane_pts = np.asarray(off_plane.points)
    with timer.stage("cluster"):
        seg = seg.model_copy(update={"cluster_eps_m": noise_adapt.cluster_radius_m(off_plane_pts, seg, config.noise)})
        clusters = cluster(off_plane_pts, seg)
        labels = np.full(len(off_plane_pts), -1, dtype=np.intp)
        for k, idx in enumerate(clusters):
            labels[idx] = k
        keep = labels >= 0
        full_clusters = assign_full_resolution(
            roi, plane.height(roi.points), off_plane_pts[keep], labels[keep], 1.5 * config.cloud.voxel_m,
            seg.min_height_m,
        )
    with timer.stage("split"):
        pieces: list[tuple[pc.PixelCloud, str, int]] = []
        for whole in full_clusters:
            cut = split_touching(whole, plane, seg.min_cluster_points)
            pieces.extend((part, cut.note, len(cut.parts) if len(cut.parts) > 1 else 0) for part in cut.parts)
    if not full_clusters:
        return _status(PerceptionStatus.NO_OBJECTS, timer, "the table is empty (no cluster above the plane)",
                       table_plane_base=plane.as_tuple(), noise=noise, height_sigma_m=height_sigma)
    hsv = None
    with timer.stage("color"):
        rgb = np.asarray(frame.color, dtype=np.uint8)
        hsv = to_hsv(frame.color)
        mask = None
        if color is not None:
            mask = color_mask(hsv, config.color.ranges[color], config.color)
    with timer.stage("geometry"):
        detections = [
            d for d in (_describe(c, plane, rgb, hsv, mask, config, seg, cluster_note=note, split_from=n)
                      for c, note, n in pieces) if d is not None
        ]
    if not detections:
        return _status(PerceptionStatus.NO_OBJECTS, timer, "no cluster large enough to be an object",
                       table_plane_base=plane.as_tuple(), noise=noise, height_sigma_m=height_sigma)
    ranked = _rank(detections, color, size_hint_m, config)
    n_colour_blobs = len(blobs(mask, config.color)) if mask is not None else 0
    if color is not None and not ranked:
        return _status(
            PerceptionStatus.NO_MATCH, timer,
            f"{len(detections)} object(s) on the table, none {color} ({n_colour_blobs} {color} blob(s) in the image)",
            table_plane_base=plane.as_tuple(), others=tuple(detections), noise=noise, height_sigma_m=height_sigma,
        )
    result = PerceptionResult(
        status=PerceptionStatus.OK,
        detections=tuple(ranked),
        timings_ms=timer.total(),
        message=f"{len(detections)} object(s); best: {ranked[0].label} at "
        + ", ".join(f"{v:.3f}" for v in ranked[0].centroid_base_m),
        table_plane_base=plane.as_tuple(),
        others=tuple(detections),
        noise=noise,
        height_sigma_m=height_sigma,
    )
    log.debug("perception: %s in %.1f ms", result.message, result.timings_ms["total"])
    return result


def _describe(
    obj: pc.PixelCloud, plane: Plane, rgb: NDArray[np.uint8], hsv: NDArray[np.uint8],
    mask: NDArray[np.uint8] | None, config: PerceptionConfig, seg: SegmentationSettings,
    *, cluster_note: str = "", split_from: int = 0,
) -> Detection | None:
    if len(obj) < seg.min_cluster_points:
        return None
    geo = object_geometry(obj.points, plane, seg)
    u, v = obj.pixels[:, 0], obj.pixels[:, 1]
    label, label_fraction = classify(hsv[v, u], config.color)
    match = float((mask[v, u] > 0).mean()) if mask is not None else label_fraction
    support = min(1.0, len(obj) / _FULL_CONFIDENCE_POINTS)
    color_name, color_rgb = dominant_color(rgb[v, u], hsv[v, u], config.color)
    centre = tuple(float(x) for x in geo.centre_base_m)
    g_axes = gravity_axes(plane, geo.yaw_rad)
    pca_centre, pca_axes, pca_extents = pca_box(obj.points)
    fill_all, fill_top = footprint_fill(obj.points, plane, geo)
    points = np.array(obj.points, dtype=np.float64)
    points.setflags(write=False)
    return Detection(
        label=label or "object",
        pixel_box=(int(u.min()), int(v.min()), int(u.max()), int(v.max())),
        centroid_base_m=tuple(float(x) for x in geo.centre_base_m),  # type: ignore[arg-type]
        size_m=(geo.length_m, geo.width_m, geo.height_m),
        yaw_rad=geo.yaw_rad,
        point_count=len(obj),
        confidence=support * (0.5 + 0.5 * match),
        color_fraction=match if mask is not None else 0.0,
        principal_axes_base=tuple(tuple(float(x) for x in row) for row in geo.principal_axes),  # type: ignore[misc]
        footprint_base_m=tuple((float(x), float(y)) for x, y in geo.footprint_base_m),
        shape="round" if geo.round else "box",
        obb=OrientedBox(centre, _rows(g_axes), (geo.length_m, geo.width_m, geo.height_m)),  # type: ignore[arg-type]
        obb_pca=OrientedBox(_vec(pca_centre), _rows(pca_axes), _vec(pca_extents)),
        principal_axis_base=_vec(pca_axes[0]),
        extents_m=_vec(pca_extents),
        points_base_m=points,
        color_name=color_name,
        color_rgb=color_rgb,
        shape_class=ShapeClass(shape_class_of(geo, fill_all, fill_top)),
        cluster_note=cluster_note,
        split_from=split_from,
    )


def _vec(v: NDArray[np.float64]) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _rows(m: NDArray[np.float64]) -> tuple[tuple[float, float, float], tuple[float, float, float],
                                           tuple[float, float, float]]:
    return (_vec(m[0]), _vec(m[1]), _vec(m[2]))


def _rank(
    detections: list[Detection], color: str | None, size_hint_m: tuple[float, float, float] | None,
    config: PerceptionConfig,
) -> list[Detection]:
    if color is not None:
        matched = [d for d in detections if d.color_fraction >= config.color.min_match_fraction]
        return sorted(matched, key=lambda d: (-d.color_fraction * d.confidence, d.centroid_base_m))
    if size_hint_m is not None:
        hint = np.asarray(size_hint_m, dtype=float)
        return sorted(detections, key=lambda d: float(np.abs(np.asarray(d.size_m) - hint).sum()))
    return sorted(detections, key=lambda d: (-d.confidence, d.size_m[1]))

