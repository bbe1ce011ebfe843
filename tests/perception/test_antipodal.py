"""Antipodal 6-DoF grasp sampling (perception/antipodal.py, object_cloud.py) on synthetic clouds (issue 28): a
box is grasped top-down, a tall cylinder from the side, a long thin rod across its long axis; seeded;
neighbours and fixtures kept clear; a round object's hidden side completed; PlanGrasp's ranking.

The clouds are sampled surfaces (sides and top, no bottom) with 1 mm of noise and normals ESTIMATED from the
points (``estimate_normals``), as an observed cloud would have them; nothing here hands the sampler a true
normal.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.perception.antipodal import (
    AntipodalSettings,
    ApproachKind,
    GraspCandidate,
    is_tall,
    rank_grasps,
    sample_grasps,
)
from bt_grasp.perception.config import GraspSettings
from bt_grasp.perception.grasps import synthesize_grasps
from bt_grasp.perception.object_cloud import ObjectCloud, box_surface, detection_cloud, estimate_normals
from bt_grasp.perception.results import Detection

NOISE_M = 0.001


def _noisy_cloud(points: np.ndarray, seed: int = 3) -> ObjectCloud:
    rng = np.random.default_rng(seed)
    pts = points + rng.normal(0.0, NOISE_M, points.shape)
    return ObjectCloud(pts, estimate_normals(pts))


def box_points(centre_xy: tuple[float, float], size: tuple[float, float, float], yaw_deg: float = 0.0,
               step: float = 0.004) -> np.ndarray:
    """Sides and top of a box standing on z = 0."""
    lx, ly, h = size
    faces = []
    zs = np.arange(step / 2, h, step)
    for axis, half, other in ((0, lx / 2, ly / 2), (1, ly / 2, lx / 2)):
        u, z = np.meshgrid(np.arange(-other, other + 1e-9, step), zs)
        for sign in (1.0, -1.0):
            p = np.zeros((u.size, 3))
            p[:, axis], p[:, 1 - axis], p[:, 2] = sign * half, u.ravel(), z.ravel()
            faces.append(p)
    gx, gy = np.meshgrid(np.arange(-lx / 2, lx / 2 + 1e-9, step), np.arange(-ly / 2, ly / 2 + 1e-9, step))
    faces.append(np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, h)]))
    local = np.vstack(faces)
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.asarray(local @ R.T + [centre_xy[0], centre_xy[1], 0.0])


def cylinder_points(centre_xy: tuple[float, float], radius: float, height: float, step: float = 0.004) -> np.ndarray:
    """Side and top of an upright cylinder standing on z = 0."""
    n = math.ceil(2 * math.pi * radius / step)
    ang = np.arange(n) * 2 * math.pi / n
    zs = np.arange(step / 2, height, step)
    a, z = np.meshgrid(ang, zs)
    side = np.column_stack([radius * np.cos(a.ravel()), radius * np.sin(a.ravel()), z.ravel()])
    g = np.arange(-radius, radius + 1e-9, step)
    gx, gy = np.meshgrid(g, g)
    inside = gx**2 + gy**2 <= radius**2
    top = np.column_stack([gx[inside], gy[inside], np.full(int(inside.sum()), height)])
    return np.asarray(np.vstack([side, top]) + np.array([centre_xy[0], centre_xy[1], 0.0]))


def _angle_to_horizontal_deg(c: GraspCandidate) -> float:
    return math.degrees(math.asin(min(1.0, abs(c.approach_base[2]))))


def test_a_box_is_grasped_top_down_across_two_faces() -> None:
    cloud = _noisy_cloud(box_points((0.5, 0.05), (0.05, 0.05, 0.05), yaw_deg=20.0))
    grasps = sample_grasps(cloud, table_z_m=0.0)
    assert grasps, "no grasp of a 5 cm cube"
    best = grasps[0]
    assert best.kind is ApproachKind.TOP_DOWN
    assert np.asarray(best.approach_base) == pytest.approx(np.asarray(best.T_base_tcp_grasp[:3, 2]))
    face_normals = [np.array([math.cos(math.radians(a)), math.sin(math.radians(a)), 0.0]) for a in (20.0, 110.0)]
    closing = np.asarray(best.closing_base)
    assert max(abs(float(closing @ n)) for n in face_normals) > math.cos(math.radians(10))
    assert best.width_m == pytest.approx(0.05, abs=0.006)
    # the tool frame is a rotation, the pre-grasp lies back along -approach, the finger tips above the table
    R = best.T_base_tcp_grasp[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.linalg.det(R) == pytest.approx(1.0)
    back = best.T_base_tcp_pregrasp[:3, 3] - best.T_base_tcp_grasp[:3, 3]
    assert back == pytest.approx(-0.10 * np.asarray(best.approach_base))
    assert best.T_base_tcp_grasp[2, 3] - 0.02 >= 0.005 - 1e-9
    assert best.terms is not None and best.terms.antipodal > math.cos(math.radians(25))


def test_a_tall_cylinder_is_grasped_from_the_side_near_its_middle() -> None:
    """A 187 mm bottle-sized cylinder: from above the fingers reach only its top third (palm face to finger
    tips is 60 mm), so the side grasps rank first."""
    height = 0.187
    cloud = _noisy_cloud(cylinder_points((0.48, 0.0), 0.029, height))
    grasps = sample_grasps(cloud, table_z_m=0.0)
    assert len(grasps) >= 3
    for c in grasps[:3]:
        assert c.kind is ApproachKind.SIDE, c.reason
        assert _angle_to_horizontal_deg(c) <= 30.0
        assert abs(c.T_base_tcp_grasp[2, 3] - height / 2) < 0.04, c.reason
        assert c.width_m == pytest.approx(0.058, abs=0.008)
    tops = [c for c in grasps if c.kind is ApproachKind.TOP_DOWN]
    assert all(c.score < grasps[0].score for c in tops)


def test_a_short_cylinder_is_still_grasped_top_down() -> None:
    """The same radius, 70 mm tall (the tabletop's green cylinder): a top-down grasp holds it at its middle."""
    cloud = _noisy_cloud(cylinder_points((0.45, 0.2), 0.025, 0.07))
    grasps = sample_grasps(cloud, table_z_m=0.0)
    assert grasps and grasps[0].kind is ApproachKind.TOP_DOWN, [c.reason for c in grasps[:3]]


# noise seeds and yaws where the contacts' noisy normals alone would tilt a top-3 squeeze 20-26 deg off
@pytest.mark.parametrize(("noise_seed", "yaw"), [(3, 35.0), (1, 35.0), (5, 0.0), (0, -50.0)])
def test_a_long_thin_rod_is_grasped_across_its_long_axis(noise_seed: int, yaw: float) -> None:
    """146 x 14 x 12 mm, longer than the gripper opens: every candidate closes across the axis. Points 2 mm
    apart (a D435 at 0.7 m samples ~1.2 mm per pixel): on a 12 mm face sparser points mix the faces' normals."""
    cloud = _noisy_cloud(box_points((0.55, -0.1), (0.146, 0.014, 0.012), yaw_deg=yaw, step=0.002), noise_seed)
    grasps = sample_grasps(cloud, table_z_m=0.0)
    assert grasps
    axis = np.array([math.cos(math.radians(yaw)), math.sin(math.radians(yaw)), 0.0])
    def off_perpendicular_deg(c: GraspCandidate) -> float:
        return math.degrees(math.asin(min(1.0, abs(float(np.asarray(c.closing_base) @ axis)))))

    assert all(off_perpendicular_deg(c) <= 20.0 for c in grasps[:3]), [c.reason for c in grasps[:3]]
    for c in grasps:  # none closes along the axis: 146 mm does not fit between the pads
        assert off_perpendicular_deg(c) <= 30.0 and c.width_m < 0.03, c.reason
    assert grasps[0].kind is ApproachKind.TOP_DOWN
    # the finger tips stay above the table although the rod is only 12 mm tall
    assert grasps[0].T_base_tcp_grasp[2, 3] >= 0.02 + 0.005 - 1e-9


def test_a_low_object_is_grasped_from_as_low_as_the_table_allows() -> None:
    """A 12 mm rod with nothing around it: a top-down grasp sits where the gripper's lowest corner (a finger tip,
    20 mm ahead of the tcp) clears the table by exactly 5 mm (25 mm up when the approach is vertical), not a
    back-off step higher (the tcp stepped back 5 mm at a time from the contacts' midpoint came to rest up to 5 mm
    too high: the pads then held only the rod's top few mm, and a household pen held so slipped out in Lift)."""
    from bt_grasp.perception.antipodal import _Gripper

    corners = _Gripper(AntipodalSettings()).corners
    cloud = _noisy_cloud(box_points((0.55, -0.1), (0.146, 0.014, 0.012), yaw_deg=20.0, step=0.002), 3)
    top_down = [c for c in sample_grasps(cloud, table_z_m=0.0) if c.kind is ApproachKind.TOP_DOWN]
    assert top_down
    for c in top_down:
        T = c.T_base_tcp_grasp
        lowest = float(np.min((corners @ T[:3, :3].T + T[:3, 3])[:, 2]))
        assert lowest == pytest.approx(0.005, abs=1e-6), c.reason


def test_too_wide_for_the_gripper_gives_no_candidate() -> None:
    cloud = _noisy_cloud(box_points((0.5, 0.0), (0.12, 0.12, 0.05)))
    assert sample_grasps(cloud, table_z_m=0.0) == ()


def test_same_seed_same_candidates_other_seed_other_samples() -> None:
    cloud = _noisy_cloud(cylinder_points((0.48, 0.0), 0.029, 0.187))
    a = sample_grasps(cloud, 0.0, rng=np.random.default_rng(5))
    b = sample_grasps(cloud, 0.0, rng=np.random.default_rng(5))
    c = sample_grasps(cloud, 0.0, rng=np.random.default_rng(6))
    assert [x.reason for x in a] == [x.reason for x in b]
    assert all(np.array_equal(x.T_base_tcp_grasp, y.T_base_tcp_grasp) for x, y in zip(a, b, strict=True))
    assert [x.reason for x in a] != [x.reason for x in c]


def test_a_neighbour_where_a_finger_would_go_rules_that_grasp_out() -> None:
    """A wall of points 15 mm beside the cube on +y: no kept grasp's open pads or palm come near it."""
    cube = _noisy_cloud(box_points((0.5, 0.0), (0.05, 0.05, 0.05)))
    wall = box_points((0.5, 0.025 + 0.015 + 0.002), (0.08, 0.004, 0.08))
    free = sample_grasps(cube, 0.0)
    crowded = sample_grasps(cube, 0.0, others_base_m=wall)
    assert any(abs(c.closing_base[1]) > 0.9 for c in free)  # closing along y: a pad on the wall's side
    assert crowded and not any(abs(c.closing_base[1]) > 0.9 and c.kind is ApproachKind.TOP_DOWN for c in crowded)


def test_unreachable_candidates_are_dropped() -> None:
    cloud = _noisy_cloud(cylinder_points((0.48, 0.0), 0.029, 0.187))
    only_from_plus_x = sample_grasps(cloud, 0.0, reachable=lambda T, _pre: bool(T[0, 2] > 0.5))
    assert only_from_plus_x and all(c.approach_base[0] > 0.5 for c in only_from_plus_x)


def test_the_friction_cone_decides_what_counts_as_antipodal() -> None:
    """With 1 mm of noise the estimated normals scatter by degrees: a 2-degree cone keeps fewer pairs."""
    cloud = _noisy_cloud(box_points((0.5, 0.0), (0.05, 0.05, 0.05)))
    narrow = sample_grasps(cloud, 0.0, settings=AntipodalSettings(friction_cone_deg=2.0))
    assert len(narrow) < len(sample_grasps(cloud, 0.0))


# --- what PlanGrasp ranks ------------------------------------------------------------------------------------


def _det(xy: tuple[float, float], size: tuple[float, float, float], shape: str, yaw_deg: float = 0.0) -> Detection:
    yaw = math.radians(yaw_deg)
    c, s = math.cos(yaw), math.sin(yaw)
    corners = tuple(
        (xy[0] + a * size[0] / 2 * c - b * size[1] / 2 * s, xy[1] + a * size[0] / 2 * s + b * size[1] / 2 * c)
        for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1))
    )
    return Detection("green", (0, 0, 1, 1), (xy[0], xy[1], size[2] / 2), size, yaw, 500, 1.0,
                     footprint_base_m=corners, shape=shape)


def test_a_block_keeps_today_s_top_down_ranking_exactly() -> None:
    block = _det((0.5, 0.0), (0.04, 0.07, 0.045), "box", yaw_deg=30.0)
    neighbour = _det((0.45, 0.2), (0.05, 0.05, 0.07), "round")
    today = synthesize_grasps(block, (neighbour,))
    ranked = rank_grasps(block, (neighbour,))
    assert ranked.ok and len(ranked.candidates) == len(today.candidates)
    for new, old in zip(ranked.candidates, today.candidates, strict=True):
        assert np.array_equal(new.T_base_tcp_grasp, old.T_base_tcp_grasp) and new.score == old.score
        assert new.kind is ApproachKind.TOP_DOWN and new.approach_base == pytest.approx((0.0, 0.0, -1.0))


def test_a_tall_detection_gets_side_grasps_first_then_the_top_down_ones() -> None:
    bottle = _det((0.48, 0.0), (0.058, 0.058, 0.187), "round")
    assert is_tall(bottle, GraspSettings()) and not is_tall(_det((0.4, 0), (0.05, 0.05, 0.07), "round"),
                                                            GraspSettings())
    ranked = rank_grasps(bottle)
    assert ranked.ok
    assert ranked.candidates[0].kind is ApproachKind.SIDE
    assert "sampled from the cloud" in ranked.message
    assert any(c.reason.startswith("across the") for c in ranked.candidates)  # the footprint's, kept after
    first_top = next(i for i, c in enumerate(ranked.candidates) if c.reason.startswith("across the"))
    assert all("antipodal grasp" in c.reason for c in ranked.candidates[:first_top])
    assert all(c.reason.startswith("across the") for c in ranked.candidates[first_top:])


def test_a_round_object_s_hidden_side_is_completed_from_its_visible_arc() -> None:
    """Perception reports a standing bottle's footprint from its top (the 26 mm cap) while the camera sees half
    of its 58 mm body: the completed cloud is the 58 mm cylinder through the visible arc, so the side grasp
    squeezes a diameter (58 mm), not a 40 mm chord that lets the bottle slip out sideways."""
    body = cylinder_points((0.48, 0.0), 0.029, 0.187)
    seen_from_plus_x = body[body[:, 0] > 0.48 - 0.002]  # the camera looks from +x: the near half of the side
    footprint = _det((0.49, 0.0), (0.026, 0.026, 0.187), "round")
    bottle = Detection(**{**footprint.__dict__, "points_base_m": seen_from_plus_x})
    cloud = detection_cloud(bottle)
    side = cloud.points_base_m[np.abs(cloud.normals_base[:, 2]) < 0.5]
    radii = np.hypot(side[:, 0] - 0.48, side[:, 1])
    assert np.median(radii) == pytest.approx(0.029, abs=0.002)
    best = sample_grasps(cloud, 0.0)[0]
    assert best.kind is ApproachKind.SIDE and best.width_m == pytest.approx(0.058, abs=0.004), best.reason
    assert np.hypot(best.T_base_tcp_grasp[0, 3] - 0.48, best.T_base_tcp_grasp[1, 3]) < 0.004  # on the axis


def test_a_known_fixture_beside_a_tall_object_is_kept_clear() -> None:
    """A fixture wall 20 mm from the bottle's side on +y: no side grasp that would put a pad (open: 42.5 to
    54.5 mm from the tcp) or the palm (40 mm behind it) into it survives; the fixture is installation data,
    given as a box, not seen."""
    from bt_grasp.geometry import make_T

    bottle = _det((0.48, 0.0), (0.058, 0.058, 0.187), "round")
    wall_T, wall_size = make_T(translation=[0.48, 0.029 + 0.020 + 0.005, 0.1]), (0.3, 0.01, 0.2)
    free = rank_grasps(bottle).candidates
    walled = rank_grasps(bottle, fixtures=[(wall_T, wall_size)]).candidates
    wall_pts = box_surface(wall_T, wall_size)
    assert wall_pts[:, 1].min() == pytest.approx(0.049) and len(wall_pts) > 500

    def gripper_max_y(c: GraspCandidate) -> float:
        """The largest base y of the open pads' and the palm's corners at the grasp (gripper.urdf's boxes)."""
        boxes = [((-0.010, 0.0425, -0.035), (0.010, 0.0545, 0.020)),
                 ((-0.010, -0.0545, -0.035), (0.010, -0.0425, 0.020)),
                 ((-0.025, -0.065, -0.080), (0.025, 0.065, -0.040))]
        corners = np.array([[x, y, z] for lo, hi in boxes for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        T = c.T_base_tcp_grasp
        return float((corners @ T[:3, :3].T + T[:3, 3])[:, 1].max())

    side_free = [c for c in free if c.kind is ApproachKind.SIDE]
    side_walled = [c for c in walled if c.kind is ApproachKind.SIDE]
    assert any(gripper_max_y(c) > 0.049 for c in side_free)  # without the wall some grasps reach its place
    assert side_walled and all(gripper_max_y(c) < 0.049 - 0.003 for c in side_walled)
