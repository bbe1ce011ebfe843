"""How far a held object may hang below its grip (``bt_grasp.behaviours.hang``): what Lift adds for the object to
rise its height. Numbers worked by hand first: the object is held at p, the middle of the stretch of the pads'
length (35 mm behind the tcp to the tips 20 mm ahead) its box fills, on the closing line; turning about p, its
centre c can end straight below p, i.e. (c_z - p_z) + |c - p| lower than it started relative to the tool."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.behaviours.hang import (
    MAX_HANG_M,
    HeldObject,
    between_pads_base_m,
    box_corners_base_m,
    hang_allowance_m,
    held_point_base_m,
    lift_rise_m,
    wall_lever_m,
)
from bt_grasp.geometry import make_T

DOWN = np.diag([1.0, -1.0, -1.0])  # tcp z (the approach) straight down, tcp y (closing) along base -y


def _top_down(x: float, y: float, z: float) -> np.ndarray:
    return make_T(DOWN, [x, y, z])


def test_a_grip_through_the_centre_adds_nothing() -> None:
    assert hang_allowance_m((0.5, 0.1, 0.03), (0.5, 0.1, 0.03)) == 0.0


def test_a_centre_straight_below_the_grip_already_hangs_as_low_as_it_can() -> None:
    # a standing bottle held near its top: its centre is 6 cm under the grip, it cannot sink further
    assert hang_allowance_m((0.5, 0.0, 0.15), (0.5, 0.0, 0.09)) == pytest.approx(0.0, abs=1e-12)


def test_a_centre_level_with_the_grip_can_sink_its_whole_lever() -> None:
    # a pan by its handle, its centre 8 cm along the handle at the grip's height
    assert hang_allowance_m((0.5, 0.0, 0.03), (0.42, 0.0, 0.03)) == pytest.approx(0.08)


def test_a_centre_above_the_grip_can_sink_more_than_its_lever() -> None:
    # held by its bottom edge, the centre 3 cm up and 4 cm across: it can swing to 5 cm below the grip
    assert hang_allowance_m((0.0, 0.0, 0.0), (0.04, 0.0, 0.03)) == pytest.approx(0.08)


def test_the_allowance_is_capped_and_needs_points() -> None:
    assert hang_allowance_m((0.0, 0.0, 0.0), (0.3, 0.0, 0.0)) == MAX_HANG_M
    assert hang_allowance_m((0.0, 0.0, 0.0), (math.nan, 0.0, 0.0)) == 0.0
    assert hang_allowance_m((0.0, math.inf, 0.0), (0.0, 0.0, 0.0)) == 0.0


def test_a_block_filling_the_pads_is_held_at_the_tcp() -> None:
    # a 4 cm high block, the tcp at its middle: it fills the pads from 2 cm above to 2 cm below (the tips)
    corners = box_corners_base_m((0.5, 0.0, 0.02), (0.05, 0.05, 0.04), 0.3)
    assert np.allclose(held_point_base_m(_top_down(0.5, 0.0, 0.02), corners), (0.5, 0.0, 0.02))


def test_a_low_object_is_held_between_its_top_and_the_finger_tips() -> None:
    # a pen 12 mm high, the tcp 25 mm up, the tips 5 mm up: held from its top (12 mm) to the tips, at 8.5 mm
    corners = box_corners_base_m((0.4, 0.1, 0.006), (0.146, 0.012, 0.012), 0.0)
    assert np.allclose(held_point_base_m(_top_down(0.43, 0.1, 0.025), corners), (0.43, 0.1, 0.0085))


def test_a_bowl_held_by_its_rim() -> None:
    # the household bowl (132 mm across, 55 mm high, centre 27.5 mm up on its axis), the tcp 62.8 mm out and
    # 36.8 mm up: it fills the pads from its rim (18.2 mm above the tcp) to the tips (20 mm below): held at
    # 35.9 mm; its centre 62.8 mm across and 8.4 mm lower can sink 63.36 - 8.4 = 54.96 mm
    box = ((0.0, 0.0, 0.0275), (0.132, 0.132, 0.055), 0.0)
    held = held_point_base_m(_top_down(0.0628, 0.0, 0.0368), box_corners_base_m(*box))
    assert np.allclose(held, (0.0628, 0.0, 0.0359))
    assert hang_allowance_m(held, box[0]) == pytest.approx(math.hypot(0.0628, 0.0084) - 0.0084)
    bowl = HeldObject((0.0, 0.0, 0.0275), (0.132, 0.132, 0.055), 0.0)  # no visible points: its box
    assert lift_rise_m(0.15, _top_down(0.0628, 0.0, 0.0368), bowl) == pytest.approx(0.15 + 0.05496, abs=1e-5)


def test_the_visible_points_between_the_pads_say_where_a_tilted_grasp_holds() -> None:
    # the tool tilted 15 degrees outwards over a rim (approach down and away from the bowl's axis): along its
    # approach the wide box's far top corners lie behind the tcp, but the material between the pads runs from
    # the tcp to 20 mm ahead of it (the wall inside the pads): held 10 mm ahead of the tcp, not behind it
    tilt = math.radians(15.0)
    R = np.array([[math.cos(tilt), 0.0, math.sin(tilt)], [0.0, -1.0, 0.0], [math.sin(tilt), 0.0, -math.cos(tilt)]])
    T = make_T(R, [0.06, 0.0, 0.055])
    approach = T[:3, 2]
    wall = np.array([T[:3, 3] + d * approach + y * T[:3, 1] for d in np.linspace(0.0, 0.02, 11)
                     for y in (-0.004, 0.0, 0.004)])
    far = np.array([[-0.06, 0.0, 0.055], [0.0, 0.06, 0.055]])  # the rim's other side: not between the pads
    points = np.vstack([wall, far])
    assert len(between_pads_base_m(T, points, 0.008)) == len(wall)
    assert np.allclose(held_point_base_m(T, between_pads_base_m(T, points, 0.008)), T[:3, 3] + 0.01 * approach)
    box = ((0.0, 0.0, 0.0275), (0.132, 0.132, 0.055), 0.0)
    from_box = held_point_base_m(T, box_corners_base_m(*box))
    assert float((from_box - T[:3, 3]) @ approach) < 0.0  # the box puts it behind the tcp
    seen = HeldObject(*box, points_base_m=points, width_m=0.008)
    expected = hang_allowance_m(T[:3, 3] + 0.01 * approach, box[0])
    assert lift_rise_m(0.15, T, seen) == pytest.approx(0.15 + expected)
    few = HeldObject(*box, points_base_m=wall[:9], width_m=0.008)  # under 10 points between the pads: the box
    assert lift_rise_m(0.15, T, few) == pytest.approx(0.15 + hang_allowance_m(from_box, box[0]))


def test_a_plate_held_by_its_rim_may_hang_from_its_outer_edge() -> None:
    # the household plate (164 mm across, 22 mm high, centre 11 mm up), held top-down 68 mm out with the pads 39 mm
    # apart (they span 48.5-87.5 mm out: the rim and the edge between them), the tcp 30 mm up. Its seen points
    # between the pads: the top near the rim and the outer edge (82 mm out). Held from its top (8 mm ahead of the
    # tcp) to the tips (20 mm): at 16 mm up. Turning about that point its centre sinks |c - p| - 5 mm = 63.2 mm; held
    # by a wall it may slide in the pads until it hangs from its edge: 82.7 mm - 5 mm = 77.7 mm (seeds 134 and 190
    # of the learned held-out set: the plate rose 13.2 and 13.5 cm of 15 with the first, 15.3 and 14.8 with the
    # second)
    T = _top_down(0.0, -0.068, 0.030)
    top = [(x, y, 0.022) for x in (-0.008, 0.0, 0.008) for y in np.linspace(-0.080, -0.052, 8)]
    edge = [(x, -math.sqrt(0.082**2 - x**2), z) for x in (-0.008, 0.0, 0.008) for z in (0.0, 0.011, 0.022)]
    beyond = [(0.0, 0.060, 0.022), (0.05, -0.03, 0.022)]  # the plate's other side and a point off the pads
    points = np.array(top + edge + beyond)
    plate = HeldObject((0.0, 0.0, 0.011), (0.164, 0.164, 0.022), 0.0, points_base_m=points, width_m=0.039)
    between = between_pads_base_m(T, points, 0.039)
    assert len(between) == len(top) + len(edge)
    held = held_point_base_m(T, between)
    assert np.allclose(held, (0.0, -0.068, 0.016))
    turn = math.hypot(0.068, 0.005) - 0.005
    assert lift_rise_m(0.15, T, plate) == pytest.approx(0.15 + turn)
    far = math.sqrt(0.082**2 + 0.011**2)  # its edge at the table or at its top, 82 mm out
    assert wall_lever_m(T, between, plate.centre_base_m) == pytest.approx(far)
    assert lift_rise_m(0.15, T, plate, by_wall=True) == pytest.approx(0.15 + far - 0.005)
    # without seen points (its box): no sliding lever, the turn alone (a box's corners are not its held wall)
    boxed = HeldObject((0.0, 0.0, 0.011), (0.164, 0.164, 0.022), 0.0)
    assert lift_rise_m(0.15, T, boxed, by_wall=True) == pytest.approx(lift_rise_m(0.15, T, boxed))
    assert hang_allowance_m(held, plate.centre_base_m, math.nan) == pytest.approx(turn)


def test_without_a_grasp_or_an_object_the_lift_is_the_height() -> None:
    bowl = HeldObject((0.0, 0.0, 0.0275), (0.132, 0.132, 0.055), 0.0)
    assert lift_rise_m(0.15, None, bowl) == 0.15
    assert lift_rise_m(0.15, _top_down(0.0628, 0.0, 0.0368), None) == 0.15
