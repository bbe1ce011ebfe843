"""Place tries the orientations that leave the held object's footprint the same and keeps the first whose
open fingers, palm and arm clear what was seen (issue 28: two 4 cm boxes 6 cm apart on one marker).

The order itself is checked on ``bt_grasp.motion.place_orientation``; the leaf tick by tick with the stand-in
robot of test_place_leaves.py (real kinematics and planner, the arm follows its targets exactly).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_place_leaves import R_DOWN, ContactRobot, run

from bt_grasp.geometry import make_T
from bt_grasp.motion.kinematics import default_kinematics
from bt_grasp.motion.place_orientation import (
    FootprintKind,
    footprint_kind,
    footprint_turns_rad,
    place_yaws,
)
from bt_grasp.perception.results import Detection, GraspCandidate

KIN = default_kinematics()
# a 4 cm cube held by a top-down grasp whose fingers close along base y (tcp y = base -y), 1 cm above its centre
HELD4 = Detection("red", (0, 0, 1, 1), (0.5, 0.0, 0.02), (0.04, 0.04, 0.04), 0.0, 100, 1.0)
GRASP4 = GraspCandidate(make_T(R_DOWN, [0.5, 0.0, 0.03]), make_T(R_DOWN, [0.5, 0.0, 0.13]), 0.04, 1.0, "test")
TARGET = (0.35, 0.2)


def neighbour(dx: float, dy: float) -> Detection:
    """A 4 cm cube already standing (dx, dy) from the place target."""
    return Detection("blue", (0, 0, 1, 1), (TARGET[0] + dx, TARGET[1] + dy, 0.02), (0.04, 0.04, 0.04), 0.0, 100, 1.0)


def tool_yaw_deg(q: np.ndarray) -> float:
    T = KIN.fk(q)
    return float(np.degrees(np.arctan2(T[1, 0], T[0, 0])))


def test_footprint_symmetries() -> None:
    assert footprint_kind(0.05, 0.03, round_footprint=False) is FootprintKind.RECTANGLE
    assert footprint_kind(0.040, 0.038, round_footprint=False) is FootprintKind.SQUARE
    assert footprint_kind(0.06, 0.06, round_footprint=True) is FootprintKind.ROUND
    deg = [round(math.degrees(t)) for t in footprint_turns_rad(FootprintKind.RECTANGLE)]
    assert deg == [0, 180]
    assert [round(math.degrees(t)) for t in footprint_turns_rad(FootprintKind.SQUARE)] == [0, 90, 180, 270]
    assert len(footprint_turns_rad(FootprintKind.ROUND)) == 12
    assert len(footprint_turns_rad(FootprintKind.RECTANGLE, free_yaw=True)) == 12


def test_the_first_candidate_is_the_one_place_always_chose_then_smallest_wrist_turn() -> None:
    # a rectangle asked at 90 deg, grasped at 80 deg: 90 first (10 deg of wrist), then 270 (-170)
    yaws = place_yaws(math.radians(90), math.radians(80), footprint_turns_rad(FootprintKind.RECTANGLE))
    assert [round(math.degrees(c.wrist_turn_rad)) for c in yaws] == [10, -170]
    # a square asked at 90 deg, grasped at 0: 90 first (not 0, though 0 turns the wrist less), then 0, 180, 270
    yaws = place_yaws(math.radians(90), 0.0, footprint_turns_rad(FootprintKind.SQUARE))
    assert [round(math.degrees(c.turn_rad)) for c in yaws] == [0, 270, 180, 90]
    assert [round(math.degrees(c.wrist_turn_rad)) for c in yaws] == [90, 0, -90, -180]
    # a round footprint: the requested yaw, then +-30, +-60, ... (positive first)
    yaws = place_yaws(0.0, 0.0, footprint_turns_rad(FootprintKind.ROUND))
    assert [round(math.degrees(c.wrist_turn_rad)) for c in yaws][:5] == [0, 30, -30, 60, -60]


def test_the_order_is_the_same_every_time() -> None:
    a = place_yaws(0.3, -1.1, footprint_turns_rad(FootprintKind.ROUND))
    b = place_yaws(0.3, -1.1, footprint_turns_rad(FootprintKind.ROUND))
    assert a == b


@pytest.mark.parametrize("turns", ["true", "false"])
def test_fingers_that_would_open_into_a_neighbour_turn_a_quarter(turns: str) -> None:
    # the neighbour stands 6 cm away along the closing direction (base y): at the requested yaw the open
    # fingers (42.5 mm each side) reach into it. With turns, a quarter turn of the cube (fingers along x)
    # clears it; without (the one orientation Place tried before), the place is blocked.
    robot = ContactRobot()
    values = {"grasp": GRASP4, "target": HELD4, "objects": (HELD4, neighbour(0.0, 0.06))}
    pose = f"{TARGET[0]};{TARGET[1]};0.0;0"
    statuses, tree = run(f'<Place pose="{pose}" turns="{turns}"/>', robot, values)
    leaf = tree.find("Place")
    if turns == "false":
        assert statuses[-1] == "FAILURE", leaf.feedback_message
        assert tree.blackboard_values()["failure_reason"] == "PLACE_BLOCKED"
        assert leaf.feedback_message.startswith("the one place orientation"), leaf.feedback_message
        return
    assert statuses[-1] == "SUCCESS", leaf.feedback_message
    # the tool (and the cube) turned a quarter: the fingers now close along base x
    assert abs(abs(tool_yaw_deg(robot.q)) - 90.0) < 0.5
    assert np.allclose(KIN.fk(robot.q)[:2, 3], TARGET, atol=1e-3)


def test_a_neighbour_across_the_fingers_keeps_the_requested_orientation() -> None:
    # the same neighbour 6 cm along x (beside the pads, not in their way): the first orientation works
    robot = ContactRobot()
    values = {"grasp": GRASP4, "target": HELD4, "objects": (HELD4, neighbour(0.06, 0.0))}
    statuses, tree = run(f'<Place pose="{TARGET[0]};{TARGET[1]};0.0;0"/>', robot, values)
    assert statuses[-1] == "SUCCESS", tree.find("Place").feedback_message
    assert abs(tool_yaw_deg(robot.q)) < 0.5 or abs(abs(tool_yaw_deg(robot.q)) - 180.0) < 0.5


def test_every_orientation_blocked_fails_place_blocked_naming_how_many() -> None:
    # neighbours on all four sides, 6 cm away: no turn of a cube clears them
    objects = (HELD4, neighbour(0.0, 0.06), neighbour(0.0, -0.06), neighbour(0.06, 0.0), neighbour(-0.06, 0.0))
    robot = ContactRobot()
    statuses, tree = run(f'<Place pose="{TARGET[0]};{TARGET[1]};0.0;0"/>', robot,
                         {"grasp": GRASP4, "target": HELD4, "objects": objects})
    assert statuses[-1] == "FAILURE"
    assert tree.blackboard_values()["failure_reason"] == "PLACE_BLOCKED"
    assert tree.find("Place").feedback_message.startswith("none of 4 place orientations works")
    assert robot.target == 0.0  # never let go
