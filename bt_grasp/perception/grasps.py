"""Top-down parallel-jaw grasps for a detected object, ranked by a stated score.

Frames: every pose is ``T_base_tcp``; tcp z points down (base -z, the approach direction), tcp y is the
closing direction (across the side the pads squeeze), tcp x = y cross z.

Depth: the tcp sits at the object's mid-height, unless the palm would then hit the object's top (a tall
object), in which case it sits ``tall_top_offset_m`` under the top; never so low that the finger tips
(``tcp_to_fingertip_m`` below the tcp) come closer than ``fingertip_clearance_m`` to the table.

Score (higher is better), the weighted sum of
  width     = (max_opening - width) / max_opening: play between the open pads and the object;
  alignment = 1 closing across the narrow side (or any side of a round object), width/length * 0.8 across
              the long side;
  clearance = min(1, d / 30 mm), d = distance from the open pads to the nearest other object's footprint;
  forward   = 1 when tcp x points away from the robot base (a tie-break between the two symmetric grasps).
Candidates whose width does not fit ``max_opening - width_margin`` are dropped (TOO_WIDE when none fits);
those whose open pads come within ``min_clearance_m`` of a neighbour are dropped (NO_CLEARANCE).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import make_T
from bt_grasp.perception.config import GraspSettings
from bt_grasp.perception.results import Detection, GraspCandidate, GraspResult, GraspStatus

log = logging.getLogger(__name__)

_CLEARANCE_FULL_M = 0.03


def tcp_height_m(det: Detection, s: GraspSettings) -> float:
    """Base-frame z of the tcp for a top-down grasp of this object."""
    table, height = det.table_z_m, det.size_m[2]
    top = table + height
    z = table + height / 2
    if z + s.palm_above_tcp_m < top + s.palm_clearance_m:  # tall: the palm would hit the top
        z = top - s.tall_top_offset_m
    return max(z, table + s.tcp_to_fingertip_m + s.fingertip_clearance_m)


def grasp_pose(centre_xy: Sequence[float], z_m: float, closing_angle_rad: float) -> NDArray[np.float64]:
    """``T_base_tcp`` with tcp z = base -z and tcp y along the closing angle (about base +z)."""
    y = np.array([np.cos(closing_angle_rad), np.sin(closing_angle_rad), 0.0])
    z = np.array([0.0, 0.0, -1.0])
    x = np.cross(y, z)
    return make_T(np.stack([x, y, z], axis=1), [centre_xy[0], centre_xy[1], z_m])


def _closing_options(det: Detection, s: GraspSettings) -> list[tuple[float, float, float, str]]:
    """(closing angle, width across, alignment, side) for each distinct squeeze of the object."""
    length, width = det.size_m[0], det.size_m[1]
    if det.shape == "round":
        step = np.deg2rad(s.round_step_deg)
        return [(float(a), max(length, width), 1.0, "round") for a in np.arange(0.0, np.pi, step)]
    across_narrow = det.yaw_rad + np.pi / 2
    options = [(float(across_narrow), width, 1.0, "narrow side")]
    options.append((float(det.yaw_rad), length, 0.8 * width / max(length, 1e-9), "long side"))
    return options


def _pad_polygons(T: NDArray[np.float64], opening_m: float, s: GraspSettings) -> list[NDArray[np.float64]]:
    """Footprints (4x2) of the two open pads in the base xy plane."""
    centre, x_axis, y_axis = T[:2, 3], T[:2, 0], T[:2, 1]
    out = []
    for side in (1.0, -1.0):
        c = centre + side * (opening_m / 2 + s.pad_thickness_m / 2) * y_axis
        hx, hy = s.pad_depth_m / 2 * x_axis, s.pad_thickness_m / 2 * y_axis
        out.append(np.array([c + hx + hy, c - hx + hy, c - hx - hy, c + hx - hy]))
    return out


def _point_segment_distance(p: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-18), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * ab)))


def _inside_convex(p: NDArray[np.float64], poly: NDArray[np.float64]) -> bool:
    signs = []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        signs.append(float((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])))
    return all(v >= 0 for v in signs) or all(v <= 0 for v in signs)


def polygon_distance(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Distance between two convex polygons (0 when they overlap)."""
    if any(_inside_convex(p, b) for p in a) or any(_inside_convex(p, a) for p in b):
        return 0.0
    best = float("inf")
    for poly, other in ((a, b), (b, a)):
        for p in poly:
            for i in range(len(other)):
                best = min(best, _point_segment_distance(p, other[i], other[(i + 1) % len(other)]))
    return best


def _footprint(det: Detection) -> NDArray[np.float64]:
    if det.footprint_base_m:
        return np.asarray(det.footprint_base_m, dtype=float)
    c = np.asarray(det.centroid_base_m[:2], dtype=float)
    r = max(det.size_m[0], det.size_m[1]) / 2
    return c + r * np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


def synthesize_grasps(
    target: Detection, neighbours: Sequence[Detection] = (), settings: GraspSettings | None = None
) -> GraspResult:
    """Ranked top-down grasps of ``target``; ``neighbours`` (other detections) are kept clear of the pads.

    The target itself may be among ``neighbours`` (it is recognised by identity or equal centroid and skipped).
    """
    s = settings or GraspSettings()
    others = [
        _footprint(d) for d in neighbours
        if d is not target and d.centroid_base_m != target.centroid_base_m
    ]
    z = tcp_height_m(target, s)
    centre = target.centroid_base_m
    radial = np.asarray(centre[:2], dtype=float)
    radial = radial / max(float(np.linalg.norm(radial)), 1e-9)
    candidates: list[GraspCandidate] = []
    widest_fit = s.max_opening_m - s.width_margin_m
    n_fit = 0
    options = _closing_options(target, s)
    for angle, width, alignment, side in options:
        if width > widest_fit:
            continue
        n_fit += 1
        for flip in (0.0, np.pi):
            T = grasp_pose(centre, z, angle + flip)
            clearance = min(
                (polygon_distance(pad, fp) for pad in _pad_polygons(T, s.max_opening_m, s) for fp in others),
                default=float("inf"),
            )
            if clearance < s.min_clearance_m:
                continue
            width_term = (s.max_opening_m - width) / s.max_opening_m
            clearance_term = min(1.0, clearance / _CLEARANCE_FULL_M)
            forward = 1.0 if float(T[:2, 0] @ radial) > 0 else 0.0
            score = (s.weight_width * width_term + s.weight_alignment * alignment
                     + s.weight_clearance * clearance_term + s.weight_forward * forward)
            pre = T.copy()
            pre[2, 3] += s.pregrasp_offset_m
            clear_txt = "no neighbour" if not np.isfinite(clearance) else f"clearance {clearance * 1e3:.0f} mm"
            reason = (f"across the {side}: width {width * 1e3:.1f} mm of {s.max_opening_m * 1e3:.0f} mm, "
                      f"{clear_txt}, tcp {z * 1e3:.1f} mm (base z)")
            candidates.append(GraspCandidate(T, pre, float(width), float(score), reason))
    if n_fit == 0:
        across = min(width for _angle, width, _alignment, _side in options)  # a round object: its widest seen
        where = "seen round, across its widest" if target.shape == "round" else "across its narrowest side"
        msg = (f"the {target.label} object is {across * 1e3:.1f} mm {where}; the gripper takes at most "
               f"{widest_fit * 1e3:.1f} mm")
        log.info("grasps: %s", msg)
        return GraspResult(GraspStatus.TOO_WIDE, (), msg)
    if not candidates:
        msg = f"every grasp that fits would put a finger within {s.min_clearance_m * 1e3:.0f} mm of a neighbour"
        log.info("grasps: %s", msg)
        return GraspResult(GraspStatus.NO_CLEARANCE, (), msg)
    candidates.sort(key=lambda c: -c.score)
    msg = f"{len(candidates)} candidate(s); best: {candidates[0].reason}"
    return GraspResult(GraspStatus.OK, tuple(candidates), msg)
