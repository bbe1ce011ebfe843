"""How far a held object can hang below its grip (``hang_allowance_m``): what Lift adds for the object to rise
its height. Numbers worked by hand first: the object turns about the grip point g, its centre c stays |c - g|
from g, so at worst it hangs straight below g, (c_z - g_z) + |c - g| lower than it started (relative to g)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.behaviours.hang import MAX_HANG_M, hang_allowance_m, lift_rise_m


def test_a_grip_through_the_centre_adds_nothing() -> None:
    assert hang_allowance_m((0.5, 0.1, 0.03), (0.5, 0.1, 0.03)) == 0.0


def test_a_centre_straight_below_the_grip_already_hangs_as_low_as_it_can() -> None:
    # a standing bottle held near its top: its centre is 6 cm under the grip, it cannot fall further
    assert hang_allowance_m((0.5, 0.0, 0.15), (0.5, 0.0, 0.09)) == pytest.approx(0.0, abs=1e-12)


def test_a_centre_level_with_the_grip_can_fall_its_whole_lever() -> None:
    # a pan by its handle, its centre 8 cm along the handle at the grip's height
    assert hang_allowance_m((0.5, 0.0, 0.03), (0.42, 0.0, 0.03)) == pytest.approx(0.08)


def test_a_bowl_held_by_its_rim() -> None:
    # the household bowl: grip 62.8 mm out from its axis, 36.8 mm up; its centre 27.5 mm up on the axis
    grip, centre = np.array([0.0628, 0.0, 0.0368]), np.array([0.0, 0.0, 0.0275])
    expected = math.hypot(0.0628, 0.0093) - 0.0093
    assert hang_allowance_m(grip, centre) == pytest.approx(expected)
    assert 0.053 < expected < 0.055


def test_a_centre_above_the_grip_can_fall_more_than_its_lever() -> None:
    # held by its bottom edge, the centre 3 cm up and 4 cm across: it can swing to 5 cm below the grip
    assert hang_allowance_m((0.0, 0.0, 0.0), (0.04, 0.0, 0.03)) == pytest.approx(0.08)


def test_the_allowance_is_capped() -> None:
    assert hang_allowance_m((0.0, 0.0, 0.0), (0.3, 0.0, 0.0)) == MAX_HANG_M


def test_the_lift_adds_the_allowance_when_the_object_and_its_grasp_are_known() -> None:
    assert lift_rise_m(0.15, None, None) == 0.15
    assert lift_rise_m(0.15, (0.0, 0.0, 0.0), None) == 0.15
    assert lift_rise_m(0.15, None, (0.1, 0.0, 0.0)) == 0.15
    assert lift_rise_m(0.15, (0.0, 0.0, 0.03), (0.05, 0.0, 0.03)) == pytest.approx(0.20)


@pytest.mark.parametrize("bad", [(math.nan, 0.0, 0.0), (0.0, math.inf, 0.0)])
def test_a_centre_that_is_not_a_point_adds_nothing(bad: tuple[float, float, float]) -> None:
    assert hang_allowance_m((0.0, 0.0, 0.0), bad) == 0.0
