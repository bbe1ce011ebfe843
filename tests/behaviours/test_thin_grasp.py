"""Grasp and Lift on a thin object (issue 28): the fingers' gap is judged against the width the grasp saw.

A 4 mm steel plate (the L bracket's upright) closes the pads to about 4 mm: under the fixed 4 mm bar, Grasp called
that grip empty (GRASP_EMPTY) though the bracket was between the fingers, and Lift called it slipped. With the
grasp on the blackboard (PlanGrasp's, whatever its width seen), a gap of 2 mm (or half a thinner width seen) is a
grip; closing on nothing (the joints' 0 limit) is still empty, with or without a grasp.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.gripper import EMPTY_WIDTH_M, empty_below_m
from bt_grasp.clock import ManualClock
from bt_grasp.tree.loader import load_tree_from_string

HOME = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence>
      <Grasp/>
      <Lift height="0.05"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@dataclass(frozen=True)
class _Seen:
    """What Grasp and Lift read of PlanGrasp's grasp: the width seen between the pads."""

    width_m: float


def _run(robot: FakeRobot, grasp: object | None) -> tuple[list[str], dict[str, object]]:
    robot.q = HOME.copy()  # the tool above the table, clear of it (Lift plans a straight line up)
    clock = ManualClock()
    tree = load_tree_from_string(TREE, robot_registry(), clock=clock)
    if grasp is not None:
        tree.root_blackboard.set("grasp", grasp)
    cell = fake_cell(robot, clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    statuses = []
    for _ in range(400):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return statuses, tree.blackboard_values()


def test_a_4_mm_plate_seen_5_5_mm_wide_is_held_and_lifted() -> None:
    robot = FakeRobot(object_width_m=0.0039)
    statuses, values = _run(robot, _Seen(0.0055))
    assert statuses[-1] == "SUCCESS", values.get("failure_reason")
    assert abs(float(values["grasp_width_m"]) - 0.0039) < 1e-9  # type: ignore[arg-type]


def test_the_same_gap_with_no_grasp_known_is_empty_as_before() -> None:
    statuses, values = _run(FakeRobot(object_width_m=0.0039), None)
    assert statuses[-1] == "FAILURE" and values["failure_reason"] == "GRASP_EMPTY"


@pytest.mark.parametrize("seen_m", [0.0055, 0.002, 0.05])
def test_closing_on_nothing_is_empty_whatever_was_seen(seen_m: float) -> None:
    statuses, values = _run(FakeRobot(object_width_m=0.0), _Seen(seen_m))
    assert statuses[-1] == "FAILURE" and values["failure_reason"] == "GRASP_EMPTY"


def test_a_plate_inside_a_wider_footprint_is_held() -> None:
    """The L bracket lying so that its footprint is 38 mm across: the pads close on its 4 mm plate (household
    seed 67: five GRASP_EMPTY in a row at a 4.0 mm gap, the bracket between the fingers)."""
    statuses, values = _run(FakeRobot(object_width_m=0.0040), _Seen(0.038))
    assert statuses[-1] == "SUCCESS", values.get("failure_reason")


def test_the_empty_bar_with_a_grasp_is_2_mm_or_half_the_width_seen() -> None:
    assert empty_below_m(None) == EMPTY_WIDTH_M  # no grasp known: as before
    assert empty_below_m(0.05) == pytest.approx(0.002)
    assert empty_below_m(0.0055) == pytest.approx(0.002)
    assert empty_below_m(0.003) == pytest.approx(0.0015)
    assert empty_below_m(0.0005) == pytest.approx(0.001)  # never under the closed limit's noise
