"""6-DoF antipodal grasp candidates from an observed object cloud (issue 28): top-down, side and across the long axis.

Input: the object's points in the robot BASE frame with outward unit normals (:class:`ObjectCloud`), the
points of everything else seen (neighbours, for clearance), and the table height. Never the simulator's mesh
or pose: the cloud is what perception saw (:mod:`bt_grasp.perception.object_cloud` makes it from a detection).

Sampling (seeded, GPD-style): draw contact points; the closing line of each runs along its inward normal; the
partner contacts are the nearest and the farthest points of the cloud on that line (within ``line_tolerance_m``,
at least ``min_width_m`` and at most the opening away) whose normals oppose the first one's within the friction
cone: the farthest spans a solid object whole, the nearest ends a thin wall, a rim, or one arm of a T or an L.
Each pair is a grasp axis (the tool's closing direction y); around it the tool may approach from any direction
perpendicular to y: the directions tried are the most vertical one (top-down when y is horizontal) and the two
horizontal ones (side grasps). Seen along the approach, an elongated cloud (``elongation_ratio``) has the closing
direction turned to lie exactly across its long axis (noisy normals tilt it otherwise; a pair whose turn would
leave the friction cone is dropped). The tcp starts on the pair's midpoint, moved along the approach towards the
centre-of-mass estimate as far as the pads still hold the contacts, then is pulled back along -approach while the
finger tips would meet the table or the open gripper (pads and palm, swept along the approach from the pre-grasp)
would come within ``min_clearance_m`` of a point it does not grasp.

Frames: ``T_base_tcp`` as everywhere, tcp z = the approach direction, tcp y = the closing direction,
tcp x = y cross z. The gripper model is bt_grasp/assets/gripper.urdf: pads 20 mm (tcp x) by 12 mm (tcp y)
by 55 mm (tcp z, from 35 mm behind the tcp to the finger tips 20 mm ahead of it), the palm 50 x 130 mm,
from 40 to 80 mm behind the tcp; opening 85 mm.

Score (higher is better), the weighted sum of the terms kept in :class:`ScoreTerms`, each in [0, 1]:
  antipodal  = how well both normals line up with the closing line (cosine of the worse one);
  clearance  = min(1, d / 30 mm), d = distance from the open pads and the palm (swept along the approach) to
               the nearest point not grasped (the object's own, the neighbours', the known fixtures') or the
               table;
  reach      = 1 when the grasp and pre-grasp poses have an IK solution (a candidate without one is dropped),
               when the caller gives a reachability test; else 1;
  approach   = how short the arm's way in is: 1 top-down, else ``side_approach_factor`` (0.5) x (1 + cos of the
               angle between the horizontal approach and the direction from the robot base to the object) / 2
               (reaching out, not back; a side approach runs low along the table with the wrist turned);
  stability  = 1 - min(1, distance from the tcp to the centre-of-mass estimate / ``stability_scale_m``):
               a grasp near the centroid of the cloud's volume estimate holds without tipping;
  width      = (max opening - width) / max opening: play between the open pads and the object.
A tall standing object is grasped from the side because a top-down grasp can reach only its top (the palm
stops 40 mm under the tcp): far from its centre of mass; a long thin one across its long axis because the
other way does not fit between the pads.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, make_T
from bt_grasp.perception import results
from bt_grasp.perception.config import GraspSettings
from bt_grasp.perception.grasps import synthesize_grasps
from bt_grasp.perception.object_cloud import ObjectCloud, box_surface, detection_cloud, fitted_surface, voxel_indices
from bt_grasp.robot_description import MAX_OPENING_M, TCP_TO_FINGERTIP_M

_DOWN = np.array([0.0, 0.0, -1.0])


#: when neither the footprint nor the sampled contacts give a grasp, contacts are drawn again this many times as
#: densely: 64 contacts over a lying pen missed the one clear stretch near its end between a bowl and a box
#: (household seed 76, NOTHING_TO_GRASP); 128 or more found it. It costs time only where nothing was found.
DENSER_SAMPLES = 4


class ApproachKind(enum.Enum):
    TOP_DOWN = "top_down"  # approach within 30 degrees of straight down
    SIDE = "side"  # approach within 30 degrees of horizontal
    OBLIQUE = "oblique"  # anything between


@dataclass(frozen=True)
class AntipodalSettings:
    """Sampling and scoring. Lengths in metres, angles in degrees."""

    max_opening_m: float = MAX_OPENING_M
    width_margin_m: float = 0.010  # play required between the object and the open pads (both sides)
    pad_half_x_m: float = 0.010  # half the pad's size along tcp x
    pad_thickness_m: float = 0.012  # pad size along the closing direction
    pad_behind_tcp_m: float = 0.035  # the pad reaches this far behind the tcp (along -approach)
    tcp_to_fingertip_m: float = TCP_TO_FINGERTIP_M  # ... and this far ahead of it
    palm_half_x_m: float = 0.025
    palm_half_y_m: float = 0.065
    palm_behind_tcp_m: float = 0.040  # the palm's face
    palm_depth_m: float = 0.040
    table_clearance_m: float = 0.005  # pads and palm stay this far above the table
    min_clearance_m: float = 0.003  # ... and this far from every point they do not grasp
    pregrasp_offset_m: float = 0.10  # the pre-grasp pose lies this far back along -approach
    samples: int = 64  # contact points drawn
    #: contacts are drawn among the points whose normal's |z| is at most this (1: all points; see rank_grasps)
    max_contact_normal_z: float = 1.0
    line_tolerance_m: float = 0.004  # a partner contact lies this close to the closing line
    min_width_m: float = 0.002  # ... and at least this far from the first (a 4 mm plate is grasped)
    friction_cone_deg: float = 25.0  # normals within this angle of the closing line count as antipodal
    min_contact_points: int = 3  # points between the pads needed to call it a grasp
    max_off_centre_m: float = 0.010  # a footprint grasp's material may lie this far off centre between the pads
    max_backoff_m: float = 0.06  # how far the tcp may be pulled back along -approach to clear the palm
    backoff_step_m: float = 0.005
    stability_scale_m: float = 0.08
    elongation_ratio: float = 2.5  # an object this many times longer than wide is grasped across its axis
    side_approach_factor: float = 0.5  # a side approach's approach term is at most this (top-down: 1)
    clearance_full_m: float = 0.03
    weight_antipodal: float = 0.3
    weight_clearance: float = 0.2
    weight_approach: float = 0.1
    weight_stability: float = 0.3
    weight_width: float = 0.1
    keep: int = 12  # the best distinct candidates returned


@dataclass(frozen=True)
class ScoreTerms:
    antipodal: float
    clearance: float
    reach: float
    approach: float
    stability: float
    width: float


@dataclass(frozen=True)
class GraspCandidate(results.GraspCandidate):
    """A parallel-jaw grasp in full 6-DoF (top-down is one case): the tool pose, its approach direction (tcp z,
    base frame), its closing direction (tcp y), the width between the contacts and the score's terms. A
    :class:`bt_grasp.perception.results.GraspCandidate` too, so planning, media and Place take it unchanged."""

    approach_base: tuple[float, float, float] = (0.0, 0.0, -1.0)
    closing_base: tuple[float, float, float] = (0.0, 1.0, 0.0)
    kind: ApproachKind = ApproachKind.TOP_DOWN
    terms: ScoreTerms | None = None


def approach_kind(approach: NDArray[np.float64]) -> ApproachKind:
    """Top-down within 30 degrees of straight down, side within 30 degrees of horizontal."""
    down = float(-approach[2])
    if down >= math.cos(math.radians(30)):
        return ApproachKind.TOP_DOWN
    if abs(down) <= math.sin(math.radians(30)):
        return ApproachKind.SIDE
    return ApproachKind.OBLIQUE


def tool_pose(centre: NDArray[np.float64], approach: NDArray[np.float64], closing: NDArray[np.float64]) -> Mat4:
    """``T_base_tcp`` with tcp z along ``approach`` and tcp y along ``closing`` (both unit, perpendicular)."""
    x = np.cross(closing, approach)
    return make_T(np.stack([x, closing, approach], axis=1), centre)


def from_top_down(candidate: results.GraspCandidate) -> GraspCandidate:
    """A top-down candidate of :mod:`bt_grasp.perception.grasps` as a 6-DoF one (same poses, score and reason)."""
    T = np.asarray(candidate.T_base_tcp_grasp, dtype=float)
    return GraspCandidate(
        candidate.T_base_tcp_grasp, candidate.T_base_tcp_pregrasp, candidate.width_m, candidate.score,
        candidate.reason, approach_base=_tuple(T[:3, 2]), closing_base=_tuple(T[:3, 1]),
        kind=approach_kind(T[:3, 2]),
    )


def _tuple(v: NDArray[np.float64]) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _unit(v: NDArray[np.float64]) -> NDArray[np.float64] | None:
    n = float(np.linalg.norm(v))
    return None if n < 1e-9 else v / n


def _approaches(closing: NDArray[np.float64]) -> list[NDArray[np.float64]]:
    """Approach directions perpendicular to the closing direction: the most downward one, two horizontal."""
    out: list[NDArray[np.float64]] = []
    down = _unit(_DOWN - float(_DOWN @ closing) * closing)
    if down is not None:
        out.append(down)
    side = _unit(np.cross(closing, np.array([0.0, 0.0, 1.0])))
    if side is not None:
        out.extend([side, -side])
    return out


def _box_distance2(p: NDArray[np.float64], lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
    """Squared distance of each point (N, 3) to an axis-aligned box (0 inside)."""
    d = np.maximum(np.maximum(lo - p, p - hi), 0.0)
    return np.asarray(np.einsum("ij,ij->i", d, d), dtype=float)


class _Gripper:
    """The open gripper's boxes in the tcp frame: the two pads swept back along the approach, and the palm."""

    def __init__(self, s: AntipodalSettings) -> None:
        half_open = s.max_opening_m / 2
        back = s.pad_behind_tcp_m + s.pregrasp_offset_m
        self.pads = [
            (np.array([-s.pad_half_x_m, half_open, -back]),
             np.array([s.pad_half_x_m, half_open + s.pad_thickness_m, s.tcp_to_fingertip_m])),
            (np.array([-s.pad_half_x_m, -half_open - s.pad_thickness_m, -back]),
             np.array([s.pad_half_x_m, -half_open, s.tcp_to_fingertip_m])),
        ]
        palm_back = s.palm_behind_tcp_m + s.palm_depth_m + s.pregrasp_offset_m
        self.palm = (np.array([-s.palm_half_x_m, -s.palm_half_y_m, -palm_back]),
                     np.array([s.palm_half_x_m, s.palm_half_y_m, -s.palm_behind_tcp_m]))
        # the region between the pads at the grasp (what the fingers close on)
        self.between = (np.array([-s.pad_half_x_m, -half_open, -s.pad_behind_tcp_m]),
                        np.array([s.pad_half_x_m, half_open, s.tcp_to_fingertip_m]))
        # the gripper's lowest-reaching corners at the grasp (tcp frame), for the table check
        self.corners = np.array([[x, y, z] for x in (-s.palm_half_x_m, s.palm_half_x_m)
                                 for y in (-half_open - s.pad_thickness_m, half_open + s.pad_thickness_m)
                                 for z in (s.tcp_to_fingertip_m, -s.palm_behind_tcp_m - s.palm_depth_m)])

        # points along the edges of those boxes (tcp frame), 3 mm apart: measured against known fixture boxes
        edges = []
        for lo, hi in [*self.pads, self.palm]:
            for axis in range(3):
                n = max(2, math.ceil(float(hi[axis] - lo[axis]) / 0.003) + 1)
                run = np.linspace(lo[axis], hi[axis], n)
                for a in (lo, hi):
                    for b in (lo, hi):
                        e = np.empty((n, 3))
                        e[:, axis] = run
                        u, v = [k for k in range(3) if k != axis]
                        e[:, u], e[:, v] = a[u], b[v]
                        edges.append(e)
        self.edges = np.vstack(edges)
        self.fixtures: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []

    def with_fixtures(self, fixtures: Sequence[tuple[Mat4, tuple[float, float, float]]]) -> _Gripper:
        """Keep known boxes (``T_base_box``, full sizes) clear too, measured exactly (:meth:`fixture_distance`)."""
        self.fixtures = [(np.linalg.inv(np.asarray(T, dtype=float)), np.asarray(size, dtype=float) / 2)
                         for T, size in fixtures]
        return self

    def fixture_distance(self, T_base_tcp: NDArray[np.float64]) -> float:
        """Distance from the gripper's box edges (at the tool pose, swept along the approach) to the nearest
        known fixture box: exact wherever a corner or an edge of the gripper is what comes nearest."""
        if not self.fixtures:
            return math.inf
        p_base = self.edges @ T_base_tcp[:3, :3].T + T_base_tcp[:3, 3]
        best = math.inf
        for T_box_base, half in self.fixtures:
            local = p_base @ T_box_base[:3, :3].T + T_box_base[:3, 3]
            best = min(best, math.sqrt(float(_box_distance2(local, -half, half).min())))
        return best

    def distance(self, p_tcp: NDArray[np.float64]) -> float:
        """Distance from the nearest of the points (tcp frame) to the gripper (boxes swept along the approach)."""
        return math.sqrt(min(float(_box_distance2(p_tcp, lo, hi).min()) for lo, hi in [*self.pads, self.palm]))


def sample_grasps(
    cloud: ObjectCloud,
    table_z_m: float,
    others_base_m: NDArray[np.float64] | None = None,
    settings: AntipodalSettings | None = None,
    rng: np.random.Generator | None = None,
    reachable: Callable[[Mat4, Mat4], bool] | None = None,
    fixtures: Sequence[tuple[Mat4, tuple[float, float, float]]] = (),
) -> tuple[GraspCandidate, ...]:
    """Ranked antipodal grasps of the object in ``cloud`` (best first, at most ``settings.keep``, distinct).

    ``others_base_m`` (M, 3): points of everything else seen, kept clear of the open gripper; ``rng`` seeds the
    contact sampling (default: seed 0); ``reachable(T_grasp, T_pregrasp)`` drops candidates the arm cannot
    reach (IK) when given; ``fixtures`` (``T_base_box``, full sizes): known boxes kept clear, measured exactly
    against the gripper's edges (``others_base_m`` may hold points on them too).
    """
    s = settings or AntipodalSettings()
    rng = rng if rng is not None else np.random.default_rng(0)
    pts = np.asarray(cloud.points_base_m, dtype=float)
    nrm = np.asarray(cloud.normals_base, dtype=float)
    if len(pts) < s.min_contact_points:
        return ()
    others = np.zeros((0, 3)) if others_base_m is None else np.asarray(others_base_m, dtype=float).reshape(-1, 3)
    com = cloud.centre_of_mass_estimate
    radial = _unit(np.array([com[0], com[1], 0.0]))
    gripper = _Gripper(s).with_fixtures(fixtures)
    cos_cone = math.cos(math.radians(s.friction_cone_deg))
    cov = np.cov((pts - pts.mean(axis=0)).T)
    found: list[GraspCandidate] = []
    if s.max_contact_normal_z >= 1.0:
        picks = rng.choice(len(pts), size=min(s.samples, len(pts)), replace=False)
    else:  # only where a closing line away from vertical starts: a wall's, a rim's, a side's points
        eligible = np.flatnonzero(np.abs(nrm[:, 2]) <= s.max_contact_normal_z)
        picks = eligible[rng.choice(len(eligible), size=min(s.samples, len(eligible)), replace=False)]
    for i in np.sort(picks):
        closing = -nrm[i]  # from the first contact into the object
        rel = pts - pts[i]
        along = rel @ closing
        off_line = np.linalg.norm(rel - np.outer(along, closing), axis=1)
        partner = ((off_line < s.line_tolerance_m) & (along > s.min_width_m) & (nrm @ closing > cos_cone)
                   & (along <= s.max_opening_m - s.width_margin_m))
        if not partner.any():
            continue
        # the farthest opposing point spans a solid object whole; the nearest is where a thin wall, a rim or
        # one arm of a T or an L ends (the farthest is then across the hollow, often too wide)
        options = np.flatnonzero(partner)
        for j in sorted({int(options[np.argmax(along[options])]), int(options[np.argmin(along[options])])}):
            found.extend(_pair_grasps(pts, nrm, i, j, float(along[j]), cos_cone, cov, others, table_z_m, com,
                                      radial, gripper, s))
    return _distinct(sorted(found, key=lambda c: -c.score), s.keep, reachable)


def _pair_grasps(
    pts: NDArray[np.float64], nrm: NDArray[np.float64], i: int, j: int, width: float, cos_cone: float,
    cov: NDArray[np.float64], others: NDArray[np.float64], table_z_m: float, com: NDArray[np.float64],
    radial: NDArray[np.float64] | None, gripper: _Gripper, s: AntipodalSettings,
) -> list[GraspCandidate]:
    """The grasps of one contact pair: one per approach direction the tool can be placed on."""
    line = _unit(pts[j] - pts[i])
    if line is None:
        return []
    antipodal = min(float(-nrm[i] @ line), float(nrm[j] @ line))
    if antipodal < cos_cone:
        return []
    centre = (pts[i] + pts[j]) / 2
    out = []
    for approach in _approaches(line):
        closing = _across_long_axis(line, approach, cov, cos_cone, s.elongation_ratio)
        if closing is None:
            continue
        cand = _place_tool(centre, approach, closing, width, antipodal, pts, others, table_z_m, com, radial,
                           gripper, s)
        if cand is not None:
            out.append(cand)
    return out


def _across_long_axis(
    line: NDArray[np.float64], approach: NDArray[np.float64], cov: NDArray[np.float64], cos_cone: float,
    ratio: float,
) -> NDArray[np.float64] | None:
    """The closing direction: the contacts' line, turned about the approach to lie exactly across the object's
    long axis as seen along the approach when the object is elongated that way (spread ``ratio`` times the
    next); None when that turn leaves the friction cone (a slanted squeeze of a rod); the line itself when the
    object is not elongated seen this way."""
    P = np.eye(3) - np.outer(approach, approach)
    values, vectors = np.linalg.eigh(P @ cov @ P)
    if values[2] < ratio**2 * max(values[1], 1e-12):
        return line
    long = vectors[:, 2]
    across = _unit(line - float(line @ long) * long)
    if across is None or float(across @ line) < cos_cone:
        return None
    return across


def _place_tool(
    centre: NDArray[np.float64], approach: NDArray[np.float64], closing: NDArray[np.float64], width: float,
    antipodal: float, pts: NDArray[np.float64], others: NDArray[np.float64], table_z: float,
    com: NDArray[np.float64], radial: NDArray[np.float64] | None, gripper: _Gripper, s: AntipodalSettings,
) -> GraspCandidate | None:
    """The tcp on the contacts' midpoint, pulled back along -approach until the gripper clears the table and
    every point it does not grasp; None when it cannot while the pads still hold the contacts."""
    # the contacts may lie anywhere along the pads: start with the tcp as near the centre of mass as that allows
    shift = float(np.clip((com - centre) @ approach, -s.tcp_to_fingertip_m, s.pad_behind_tcp_m))
    start = centre + shift * approach
    if approach[2] < -0.5:  # from above: start no lower than where the gripper's lowest corner clears the table
        R = tool_pose(start, approach, closing)[:3, :3]
        below = table_z + s.table_clearance_m - (float(np.min((gripper.corners @ R.T)[:, 2])) + float(start[2]))
        if below > 0.0:  # backing off along -approach raises the tool by -approach[2] per metre
            start = start - (below / -float(approach[2]) + 1e-9) * approach
    steps = round(s.max_backoff_m / s.backoff_step_m)
    for k in range(steps + 1):
        tcp = start - k * s.backoff_step_m * approach
        T = tool_pose(tcp, approach, closing)
        R, t = T[:3, :3], T[:3, 3]
        lowest = float(np.min((gripper.corners @ R.T + t)[:, 2]))
        if lowest < table_z + s.table_clearance_m:
            if approach[2] < -0.5:  # top-down: backing off raises the gripper
                continue
            return None
        local = (pts - t) @ R
        lo, hi = gripper.between
        inside = np.all((local >= lo) & (local <= hi), axis=1)
        if int(inside.sum()) < s.min_contact_points:
            return None  # backed off past the contacts
        held = local[inside]
        width_held = float(held[:, 1].max() - held[:, 1].min())
        if width_held > s.max_opening_m - s.width_margin_m:
            return None
        free = local[~inside]
        if len(others):
            free = np.vstack([free, (others - t) @ R])
        dist = min(gripper.distance(free) if len(free) else math.inf, gripper.fixture_distance(T))
        if dist < s.min_clearance_m:
            continue  # the palm or a pad (on its way in) meets a point, or nearly: back off
        table_gap = lowest - table_z
        clearance = min(dist, table_gap)
        return _scored(T, approach, closing, max(width, width_held), antipodal, clearance, com, radial, s)
    return None


def _scored(
    T: Mat4, approach: NDArray[np.float64], closing: NDArray[np.float64], width: float, antipodal: float,
    clearance: float, com: NDArray[np.float64], radial: NDArray[np.float64] | None, s: AntipodalSettings,
) -> GraspCandidate:
    kind = approach_kind(approach)
    horizontal = _unit(np.array([approach[0], approach[1], 0.0]))
    if kind is ApproachKind.TOP_DOWN or horizontal is None or radial is None:
        approach_term = 1.0
    else:  # the arm's way in is longer from the side: low along the table, the wrist turned
        approach_term = s.side_approach_factor * (1.0 + float(horizontal @ radial)) / 2
    terms = ScoreTerms(
        antipodal=float(np.clip(antipodal, 0.0, 1.0)),
        clearance=min(1.0, clearance / s.clearance_full_m),
        reach=1.0,
        approach=approach_term,
        stability=1.0 - min(1.0, float(np.linalg.norm(T[:3, 3] - com)) / s.stability_scale_m),
        width=max(0.0, (s.max_opening_m - width) / s.max_opening_m),
    )
    score = (s.weight_antipodal * terms.antipodal + s.weight_clearance * terms.clearance
             + s.weight_approach * terms.approach + s.weight_stability * terms.stability
             + s.weight_width * terms.width)
    pre = T.copy()
    pre[:3, 3] -= s.pregrasp_offset_m * approach
    a = approach
    reason = (f"{kind.value} antipodal grasp, approach ({a[0]:+.2f}, {a[1]:+.2f}, {a[2]:+.2f}), width "
              f"{width * 1e3:.1f} mm, antipodal {terms.antipodal:.2f}, stability {terms.stability:.2f}, "
              f"clearance {clearance * 1e3:.0f} mm, tcp z {T[2, 3] * 1e3:.1f} mm (base)")
    return GraspCandidate(T, pre, float(width), float(score), reason, approach_base=_tuple(approach),
                          closing_base=_tuple(closing), kind=kind, terms=terms)


def near_same(a: results.GraspCandidate, b: results.GraspCandidate) -> bool:
    """Whether two grasps are near-identical: tcp within 15 mm, approach (tcp z) and closing (tcp y) within
    20 deg (a closing direction and its opposite are the same grasp)."""
    cos20 = math.cos(math.radians(20))
    Ta, Tb = np.asarray(a.T_base_tcp_grasp, dtype=float), np.asarray(b.T_base_tcp_grasp, dtype=float)
    return bool(np.linalg.norm(Ta[:3, 3] - Tb[:3, 3]) < 0.015 and float(Ta[:3, 2] @ Tb[:3, 2]) > cos20
                and abs(float(Ta[:3, 1] @ Tb[:3, 1])) > cos20)


def _distinct(
    ranked: Sequence[GraspCandidate], keep: int, reachable: Callable[[Mat4, Mat4], bool] | None
) -> tuple[GraspCandidate, ...]:
    """The best reachable one of each group of near-identical grasps (tcp within 15 mm, approach and closing
    within 20 deg; a closing direction and its opposite are the same grasp), best first."""
    out: list[GraspCandidate] = []
    for c in ranked:
        if any(near_same(c, o) for o in out):
            continue
        if reachable is not None and not reachable(c.T_base_tcp_grasp, c.T_base_tcp_pregrasp):
            continue
        out.append(c)
        if len(out) >= keep:
            break
    return tuple(out)


# ------------------------------------------------------------------------------------------------------------
# what PlanGrasp asks for


def is_tall(det: results.Detection, s: GraspSettings) -> bool:
    """Taller than twice what the fingers span from above (palm face to finger tips): a top-down grasp would
    hold it by its top third, far above its centre of mass (a standing bottle or can, not a block)."""
    return det.size_m[2] > 2 * (s.palm_above_tcp_m + s.tcp_to_fingertip_m)


def rank_grasps(
    target: results.Detection,
    neighbours: Sequence[results.Detection] = (),
    grasp_settings: GraspSettings | None = None,
    settings: AntipodalSettings | None = None,
    reachable: Callable[[Mat4, Mat4], bool] | None = None,
    seed: int = 0,
    fixtures: Sequence[tuple[Mat4, tuple[float, float, float]]] = (),
    viewpoint_base_m: Sequence[float] | None = None,
) -> results.GraspResult:
    """The grasps PlanGrasp tries, in order, as 6-DoF candidates.

    An object a top-down grasp holds near its middle keeps the footprint's top-down ranking of
    :func:`bt_grasp.perception.grasps.synthesize_grasps` unchanged (the colour-block scenes' runs stay as
    they were), as long as the visible points bear each of those grasps out (:func:`fits_seen_points`: something
    between the pads, nothing under them). A tall object (:func:`is_tall`), one with no top-down grasp, or one
    whose footprint grasps the visible points refute (the footprint's centre over an L's or a T's empty corner, a
    pad landing on a mug's rim) gets the antipodal candidates sampled from its cloud first (seeded by ``seed``;
    only reachable ones when ``reachable`` is given), the footprint's borne-out top-down ones after them; when
    there are none of either, contacts are drawn again :data:`DENSER_SAMPLES` times as densely, and then as
    densely among the points whose normals lie more than the friction cone from vertical only (a plate seen from
    above is mostly its face, whose contacts pair with nothing the camera sees; its rim's few points are what a grasp
    can close on: household learned seed 194, 1 of 256 contacts drawn had a partner).
    ``fixtures``: the known fixtures' solid parts as (``T_base_box``, full sizes), kept clear of the open gripper
    like the objects seen. ``viewpoint_base_m``: where the camera that saw the target was (orients the visible
    points' normals: :func:`bt_grasp.perception.object_cloud.estimate_normals`).
    """
    gs = grasp_settings or GraspSettings()
    s = settings or AntipodalSettings(pregrasp_offset_m=gs.pregrasp_offset_m)
    top = synthesize_grasps(target, neighbours, gs)
    top_all = tuple(from_top_down(c) for c in top.candidates)
    top_list = tuple(c for c in top_all if fits_seen_points(c, target, s))
    refuted = len(top_all) - len(top_list)
    if top.ok and not is_tall(target, gs) and not refuted:
        return results.GraspResult(top.status, top_list, top.message)
    sampled = sampled_grasps(target, neighbours, s, reachable, seed, fixtures, viewpoint_base_m)
    if not sampled and not top_list:  # nothing at all: look harder before giving up (a narrow clear stretch)
        denser = replace(s, samples=DENSER_SAMPLES * s.samples)
        sampled = sampled_grasps(target, neighbours, denser, reachable, seed, fixtures, viewpoint_base_m)
    if not sampled and not top_list:  # still nothing: draw only where a wall or a rim can start a grasp
        walls = replace(s, samples=DENSER_SAMPLES * s.samples,
                        max_contact_normal_z=math.cos(math.radians(s.friction_cone_deg)))
        sampled = sampled_grasps(target, neighbours, walls, reachable, seed, fixtures, viewpoint_base_m)
    candidates = sampled + top_list
    if not candidates:
        if top.ok:  # every footprint grasp refuted, nothing sampled
            return results.GraspResult(
                results.GraspStatus.NO_CLEARANCE, (),
                f"the visible points refute all {refuted} top-down grasp(s) of the footprint and no antipodal pair "
                "of the cloud fits the gripper")
        return top
    if not top.ok:
        why = f"no top-down grasp ({top.message})"
    elif refuted:
        why = f"the visible points refute {refuted} of {len(top_all)} top-down grasp(s) of the footprint"
    else:
        why = "tall for a top-down grasp"
    message = (f"{len(candidates)} candidate(s) ({len(sampled)} sampled from the cloud: {why}); "
               f"best: {candidates[0].reason}")
    return results.GraspResult(results.GraspStatus.OK, candidates, message)


def sampled_grasps(
    target: results.Detection,
    neighbours: Sequence[results.Detection] = (),
    settings: AntipodalSettings | None = None,
    reachable: Callable[[Mat4, Mat4], bool] | None = None,
    seed: int = 0,
    fixtures: Sequence[tuple[Mat4, tuple[float, float, float]]] = (),
    viewpoint_base_m: Sequence[float] | None = None,
) -> tuple[GraspCandidate, ...]:
    """The antipodal candidates sampled from the target's cloud (:func:`sample_grasps`), the neighbours' fitted
    shapes and visible points and the fixtures kept clear: what :func:`rank_grasps` puts first for an object
    with no good footprint grasp, and what PlanGrasp falls back on when every footprint grasp it was given is
    blocked (a lying pen whose centre lies beside a standing mug: the palm across it meets the mug; grasps
    sampled along the pen lie clear of it). Same arguments as :func:`rank_grasps`, same result for the same
    seed."""
    s = settings or AntipodalSettings()
    seen = [d for d in neighbours if d is not target and d.centroid_base_m != target.centroid_base_m]
    others = [fitted_surface(d).points_base_m for d in seen]
    for d in seen:
        if d.points_base_m is not None:
            pts = np.asarray(d.points_base_m, dtype=float).reshape(-1, 3)
            others.append(pts[voxel_indices(pts, 0.005)])
    others += [box_surface(T, size) for T, size in fixtures]
    other_points = np.vstack(others) if others else None
    cloud = detection_cloud(target, viewpoint_base_m=viewpoint_base_m)
    return sample_grasps(cloud, target.table_z_m, other_points, s, np.random.default_rng(seed), reachable, fixtures)


def fits_seen_points(candidate: GraspCandidate, target: results.Detection, s: AntipodalSettings) -> bool:
    """Whether the target's visible points bear out a grasp computed from its footprint: at least
    ``min_contact_points`` of them between the pads where they close, centred between them within
    ``max_off_centre_m`` (the footprint's centre over an L's empty corner holds one arm near a pad), and none
    inside the open pads or the palm on their way in (a pad would land on the object). True when the detection
    carries no points to judge by."""
    if target.points_base_m is None or len(target.points_base_m) < 10:
        return True
    pts = np.asarray(target.points_base_m, dtype=float).reshape(-1, 3)
    pts = pts[voxel_indices(pts, 0.003)]
    T = np.asarray(candidate.T_base_tcp_grasp, dtype=float)
    local = (pts - T[:3, 3]) @ T[:3, :3]
    gripper = _Gripper(s)
    lo, hi = gripper.between
    between = np.all((local >= lo) & (local <= hi), axis=1)
    if int(between.sum()) < s.min_contact_points:
        return False
    held = local[between, 1]
    if abs(float(held.max() + held.min()) / 2) > s.max_off_centre_m:
        return False  # one pad would shove the object that far before the other touches it
    rest = local[~between]
    return not len(rest) or gripper.distance(rest) > 0.0
