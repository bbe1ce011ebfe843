"""Lift with the object it holds (``target``): the object's centre rises the height, whatever it hangs by.

Stand-ins, no simulator (the robot follows joint targets at once; kinematics and Cartesian lines are real). The
grasp on the blackboard grips at the tool's position; the perceived object's centre is put beside or below it.
The object's box is 4 cm high, centred on its centre: held level with the tool it fills the pads from 2 cm above
the tcp to the finger tips 2 cm below, so it is held at the tcp. Expected rises worked by hand from
``bt_grasp.behaviours.hang``: a centre 5 cm beside the grip at its height can sink 5 cm by turning about the grip,
so the tool rises 15 + 5 cm; a centre straight under the grip cannot sink, so 15 cm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import Cell
from bt_grasp.clock import ManualClock
from bt_grasp.geometry import Mat4
from bt_grasp.perception.results import Detection
from bt_grasp.tree.loader import load_tree_from_string

HOME = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])  # the tool 0.33 m up; a straight line up reaches 0.36 m more


@dataclass(frozen=True)
class _Grasp:
    T_base_tcp_grasp: Mat4
    width_m: float = 0.02


def _object_at(centre: np.ndarray) -> Detection:
    return Detection("object", (0, 0, 1, 1), (float(centre[0]), float(centre[1]), float(centre[2])),
                     (0.05, 0.05, 0.04), 0.0, 100, 1.0)


def _lift(xml: str, centre_offset_m: tuple[float, float, float] | None) -> tuple[list[str], float]:
    """Tick ``xml`` to its end; the statuses and how far the tool rose."""
    clock, robot = ManualClock(), FakeRobot(object_width_m=0.02)
    robot.q, robot.width, robot.target = HOME.copy(), 0.02, 0.0
    cell: Cell = fake_cell(robot, clock)
    T_tool = cell.kinematics.fk(HOME)
    tree = load_tree_from_string(f'<root BTCPP_format="4"><BehaviorTree ID="T">{xml}</BehaviorTree></root>',
                                 robot_registry(), clock=clock)
    tree.root_blackboard.set("grasp", _Grasp(T_tool))
    if centre_offset_m is not None:
        tree.root_blackboard.set("target", _object_at(T_tool[:3, 3] + np.asarray(centre_offset_m)))
    for node in tree.nodes():
        node.setup(cell=cell)
    statuses = []
    for _ in range(3000):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return statuses, float(cell.kinematics.fk(robot.q)[2, 3] - T_tool[2, 3])


WITH_TARGET = '<Lift height="0.15" target="{target}"/>'


@pytest.mark.parametrize(("offset", "rise"), [
    ((0.05, 0.0, 0.0), 0.20),  # level with the grip, 5 cm aside: it can sink 5 cm
    ((0.0, 0.03, 0.0), 0.18),  # 3 cm aside: 3 cm
    # 4 cm lower: it fills the pads from 2 cm below the tcp to the tips, held 2 cm below the tcp, its centre 2 cm
    # under that: straight below where it is held, it cannot sink
    ((0.0, 0.0, -0.04), 0.15),
    ((0.0, 0.0, 0.0), 0.15),  # gripped through its centre
])
def test_the_tool_rises_the_height_plus_how_far_the_object_can_hang(offset: tuple[float, float, float],
                                                                     rise: float) -> None:
    statuses, risen = _lift(WITH_TARGET, offset)
    assert statuses[-1] == "SUCCESS" and set(statuses[:-1]) == {"RUNNING"}
    assert risen == pytest.approx(rise, abs=1e-3)


def test_without_a_target_the_tool_rises_the_height_as_before() -> None:
    statuses, risen = _lift('<Lift height="0.15"/>', (0.05, 0.0, 0.0))
    assert statuses[-1] == "SUCCESS"
    assert risen == pytest.approx(0.15, abs=1e-3)


def test_with_no_object_perceived_the_tool_rises_the_height() -> None:
    statuses, risen = _lift(WITH_TARGET, None)
    assert statuses[-1] == "SUCCESS"
    assert risen == pytest.approx(0.15, abs=1e-3)


def test_out_of_reach_with_the_hang_the_tool_rises_the_height_alone() -> None:
    # 0.34 m up is reachable from HOME, 0.34 + 0.05 m is not (the arm's reach)
    statuses, risen = _lift('<Lift height="0.34" target="{target}"/>', (0.05, 0.0, 0.0))
    assert statuses[-1] == "SUCCESS"
    assert risen == pytest.approx(0.34, abs=1e-3)
