"""Free placement on a container's floor (bt_grasp.motion.free_area): pure geometry, no simulator.

The floor is the household bin's (36 x 24 cm inside, walls 46 mm above its floor); the robot's base lies off
its -x, -y corner, as it does in scenes/household_clear.yaml."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.geometry import make_T
from bt_grasp.motion.free_area import Floor, HeldShape, Resting, Spot, ToolPart, free_spots

FLOOR = Floor(0.18, 0.12, 0.046)
BASE = (-0.30, -0.52)
M = 0.01  # margin


def _pads(width_m: float, tcp_z_m: float) -> tuple[ToolPart, ...]:
    """Two finger pads (20 x 12 x 55 mm) closing along the object's y on an object ``width_m`` wide, their
    tips 20 mm under the tool point at ``tcp_z_m`` above the floor, and the palm (50 x 130 x 40 mm) above."""
    pads = tuple(ToolPart((0.02, 0.012, 0.055), make_T(np.eye(3), [0.0, s * (0.0425 + 0.006), tcp_z_m + 0.0075]))
                 for s in (-1, 1))
    return (*pads, ToolPart((0.05, 0.13, 0.04), make_T(np.eye(3), [0.0, 0.0, tcp_z_m + 0.06])))


def _rect(spot: Spot, length: float, width: float, grow: float = M) -> tuple[float, float, float, float]:
    c, s = abs(math.cos(spot.yaw_rad)), abs(math.sin(spot.yaw_rad))
    hx, hy = (c * length + s * width) / 2 + grow, (s * length + c * width) / 2 + grow
    return spot.x_m - hx, spot.x_m + hx, spot.y_m - hy, spot.y_m + hy


def test_the_first_object_goes_into_the_corner_farthest_from_the_robot() -> None:
    box = HeldShape(0.065, 0.045, 0.03, False)
    best = free_spots(FLOOR, [], box, margin_m=M, far_from_xy=BASE)[0]
    x0, x1, y0, y1 = _rect(best, 0.065, 0.045)
    assert x1 == pytest.approx(0.18) and y1 == pytest.approx(0.12)  # the +x, +y corner, against both walls
    assert best.contact_m == pytest.approx((x1 - x0) + (y1 - y0))


def test_the_next_object_packs_against_the_first_and_a_wall() -> None:
    first = Resting((0.18 - 0.0425, 0.12 - 0.0325), 0.0, (0.065, 0.045), 0.03)
    box = HeldShape(0.065, 0.045, 0.03, False)
    spots = free_spots(FLOOR, [first], box, margin_m=M, far_from_xy=BASE)
    best = spots[0]
    x0, x1, y0, y1 = _rect(best, 0.065, 0.045)
    # against the first object's grown side and the far wall: two whole sides, as good as a corner
    assert x1 == pytest.approx(0.18 - 0.085) and y1 == pytest.approx(0.12)
    assert best.contact_m == pytest.approx((x1 - x0) + (y1 - y0))
    for spot in spots:  # never on the first one (each footprint grown by the margin)
        a0, a1, _, b1 = _rect(spot, 0.065, 0.045)
        assert a1 <= 0.18 - 0.085 + 1e-9 or b1 <= 0.12 - 0.065 + 1e-9 or a0 >= 0.18 + 1e-9


def test_an_object_too_big_for_what_is_left_has_no_spot() -> None:
    assert free_spots(FLOOR, [], HeldShape(0.40, 0.30, 0.03, False), margin_m=M) == []
    full = [Resting((0.0, 0.0), 0.0, (0.34, 0.22), 0.05)]
    assert free_spots(FLOOR, full, HeldShape(0.05, 0.05, 0.03, False), margin_m=M) == []


def test_the_open_fingers_stay_inside_the_walls_and_off_the_placed_objects() -> None:
    # a 45 mm wide box closed on across its width: the pads stand 54.5 mm off its centre, low down
    box = HeldShape(0.065, 0.045, 0.03, False, _pads(0.045, 0.015))
    first = Resting((0.10, 0.0), 0.0, (0.10, 0.05), 0.03)
    spots = free_spots(FLOOR, [first], box, margin_m=M, far_from_xy=BASE)
    assert spots
    for spot in spots:
        c, s = math.cos(spot.yaw_rad), math.sin(spot.yaw_rad)
        for side in (-1, 1):  # each pad's centre (the pads close along the object's y)
            px, py = spot.x_m - s * side * 0.0485, spot.y_m + c * side * 0.0485
            assert abs(px) <= 0.18 - 0.01 + 1e-9 and abs(py) <= 0.12 - 0.006 + 1e-9
            # the pad (20 x 12 mm, turned with the object) stays off the first box's grown footprint
            hxp, hyp = abs(c) * 0.01 + abs(s) * 0.006, abs(s) * 0.01 + abs(c) * 0.006
            assert px + hxp <= 0.04 + 1e-9 or px - hxp >= 0.16 - 1e-9 or abs(py) >= 0.035 + hyp - 1e-9
    # the best spot is not against a wall with its pads' side: the pads would be in the wall
    best = spots[0]
    _, _, y0, y1 = _rect(best, 0.065, 0.045)
    pads_along_y = abs(math.cos(best.yaw_rad)) > 0.5
    assert not (pads_along_y and (y1 == pytest.approx(0.12) or y0 == pytest.approx(-0.12)))


def test_the_palm_may_pass_over_a_low_object_but_not_a_standing_one() -> None:
    # a thin object (pen-like, 12 mm) grasped at its top: the palm is 130 mm long across it, 34-74 mm up
    pen = HeldShape(0.135, 0.012, 0.012, False, _pads(0.012, 0.012)[2:])
    low = Resting((0.0, 0.0), 0.0, (0.10, 0.03), 0.025)
    can = Resting((0.0, 0.0), 0.0, (0.10, 0.03), 0.122)  # as wide, but standing 122 mm
    near_low = [s for s in free_spots(FLOOR, [low], pen, margin_m=M) if abs(s.x_m) < 0.03 and abs(s.y_m) < 0.08]
    near_can = [s for s in free_spots(FLOOR, [can], pen, margin_m=M) if abs(s.x_m) < 0.03 and abs(s.y_m) < 0.08]
    assert near_low  # lying beside the low box, its palm above the box
    assert not near_can  # beside the can, the palm would come down on it


def test_a_round_footprint_is_tried_every_30_degrees_and_the_order_is_fixed() -> None:
    can = HeldShape(0.057, 0.057, 0.12, True)
    spots = free_spots(FLOOR, [], can, margin_m=M, far_from_xy=BASE, limit=12)
    assert len(spots) == 12 and len({(s.x_m, s.y_m) for s in spots}) == 1
    assert sorted(round(math.degrees(s.yaw_rad)) for s in spots) == list(range(0, 360, 30))
    assert free_spots(FLOOR, [], can, margin_m=M, far_from_xy=BASE, limit=12) == spots


def test_five_household_objects_fit_one_after_the_other() -> None:
    """The household set's perceived sizes, the gripper as above, each set down where the first spot says."""
    objects = [  # length, width, height, round, pads closing across the width, tool point height
        (0.057, 0.057, 0.121, True, 0.06), (0.158, 0.044, 0.025, False, 0.012), (0.082, 0.045, 0.029, False, 0.015),
        (0.065, 0.045, 0.030, False, 0.015), (0.135, 0.011, 0.011, False, 0.006)]
    resting: list[Resting] = []
    for length, width, height, round_, tcp_z in objects:
        held = HeldShape(length, width, height, round_, () if round_ else _pads(width, tcp_z))
        spots = free_spots(FLOOR, resting, held, margin_m=M, far_from_xy=BASE, limit=1)
        assert spots, f"no spot for {length} x {width} after {len(resting)}"
        s = spots[0]
        resting.append(Resting((s.x_m, s.y_m), s.yaw_rad, (length, width), height))


def test_the_footprint_keeps_its_wall_margin_from_the_walls_and_its_margin_from_the_objects() -> None:
    box = HeldShape(0.065, 0.045, 0.03, False)
    first = Resting((0.10, 0.0), 0.0, (0.10, 0.05), 0.03)
    spots = free_spots(FLOOR, [first], box, margin_m=M, wall_margin_m=0.02, far_from_xy=BASE)
    assert spots
    for spot in spots:
        x0, x1, y0, y1 = _rect(spot, 0.065, 0.045, grow=0.02)  # 2 cm round it: inside the walls
        assert x0 >= -0.18 - 1e-9 and x1 <= 0.18 + 1e-9 and y0 >= -0.12 - 1e-9 and y1 <= 0.12 + 1e-9
    # beside the object it may pack at the margin (1 cm each: 2 cm apart), not at the wall margin
    def touches_first(spot: Spot) -> bool:
        a0, a1, b0, b1 = _rect(spot, 0.065, 0.045)
        beside_x = (abs(a1 - 0.04) < 1e-6 or abs(a0 - 0.16) < 1e-6) and b0 < 0.035 and b1 > -0.035
        beside_y = (abs(b1 + 0.035) < 1e-6 or abs(b0 - 0.035) < 1e-6) and a0 < 0.16 and a1 > 0.04
        return beside_x or beside_y

    assert any(touches_first(spot) for spot in spots)
