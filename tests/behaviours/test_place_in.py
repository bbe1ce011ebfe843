"""PlaceIn tick by tick with a stand-in robot (real kinematics and planner, scenes/household_clear.yaml's bin):
the held object goes anywhere free on the bin's floor, clear of what was set down there before (``placed``),
and a bin with no room fails PLACE_BLOCKED before the arm moves."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from behaviour_fakes import FakeCamera
from test_place_leaves import GRASP, HELD, KIN, ContactRobot

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import make_cell
from bt_grasp.behaviours.place_in import DEFAULT_MARGIN_M, DEFAULT_WALL_MARGIN_M
from bt_grasp.clock import ManualClock
from bt_grasp.motion.executor import ExecutorOptions
from bt_grasp.motion.planner import PlannerOptions, default_planner
from bt_grasp.motion.trajectory import MotionLimits
from bt_grasp.perception.results import Detection
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene.format import load_scene
from bt_grasp.tree.loader import load_tree_from_string

REPO = Path(__file__).resolve().parents[2]
SCENE = load_scene(REPO / "scenes" / "household_clear.yaml")
BIN = next(f for f in SCENE.fixtures if f.name == "bin")


def run(body: str, robot: ContactRobot, values: dict[str, Any], ticks: int = 4000) -> tuple[list[str], Any]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    clock = ManualClock()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = make_cell(robot, FakeCamera(), clock, SCENE, seed=0)  # type: ignore[arg-type]
    cell.kinematics, cell.planner, cell.planner_options = KIN, default_planner(), PlannerOptions(seed=1)
    cell.motion_limits, cell.executor_options = MotionLimits(), ExecutorOptions(settle_timeout_s=0.3)
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in values.items():
        tree.root_blackboard.set(key, value)
    statuses: list[str] = []
    for _ in range(ticks):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return statuses, tree


def _inside_bin(det: Detection, grow_m: float = 0.0) -> bool:
    """The detection's footprint (turned, grown) lies inside the bin's walls (the base is the world here)."""
    c, s = abs(np.cos(det.yaw_rad)), abs(np.sin(det.yaw_rad))
    hx = (c * det.size_m[0] + s * det.size_m[1]) / 2 + grow_m
    hy = (s * det.size_m[0] + c * det.size_m[1]) / 2 + grow_m
    dx, dy = abs(det.centroid_base_m[0] - BIN.center_xy_m[0]), abs(det.centroid_base_m[1] - BIN.center_xy_m[1])
    return dx + hx <= BIN.inner_size_m[0] / 2 + 1e-6 and dy + hy <= BIN.inner_size_m[1] / 2 + 1e-6


def _apart(a: Detection, b: Detection, gap_m: float) -> bool:
    """Their turned footprints' boxes are at least ``gap_m`` apart along x or y."""
    def box(d: Detection) -> tuple[float, float, float, float]:
        c, s = abs(np.cos(d.yaw_rad)), abs(np.sin(d.yaw_rad))
        hx, hy = (c * d.size_m[0] + s * d.size_m[1]) / 2, (s * d.size_m[0] + c * d.size_m[1]) / 2
        x, y = d.centroid_base_m[0], d.centroid_base_m[1]
        return x - hx, x + hx, y - hy, y + hy

    ax0, ax1, ay0, ay1 = box(a)
    bx0, bx1, by0, by1 = box(b)
    return max(bx0 - ax1, ax0 - bx1) >= gap_m - 1e-6 or max(by0 - ay1, ay0 - by1) >= gap_m - 1e-6


def test_place_in_sets_the_object_down_inside_the_bin_and_remembers_it() -> None:
    # RUNNING while choosing, carrying, descending, opening and retreating; SUCCESS with the fingers open, the
    # box set down on the bin's floor (4 mm) inside its walls, and kept in {placed}
    robot = ContactRobot()
    statuses, tree = run('<PlaceIn fixture="bin"/>', robot, {"grasp": GRASP, "target": HELD, "objects": ()})
    assert statuses[-1] == "SUCCESS", tree.find("PlaceIn").feedback_message
    assert robot.target == MAX_OPENING_M
    placed = tree.root_blackboard.get("placed")
    assert len(placed) == 1 and _inside_bin(placed[0], DEFAULT_WALL_MARGIN_M)
    assert placed[0].centroid_base_m[2] == pytest.approx(BIN.surface_z_m + 0.025, abs=1e-3)


def test_place_in_keeps_clear_of_what_it_set_down_before() -> None:
    robot = ContactRobot()
    values = {"grasp": GRASP, "target": HELD, "objects": ()}
    statuses, tree = run('<PlaceIn fixture="bin"/>', robot, values)
    first = tree.root_blackboard.get("placed")[0]
    robot2 = ContactRobot()
    statuses, tree = run('<PlaceIn fixture="bin"/>', robot2, {**values, "placed": (first,)})
    assert statuses[-1] == "SUCCESS", tree.find("PlaceIn").feedback_message
    placed = tree.root_blackboard.get("placed")
    assert len(placed) == 2 and placed[0] == first
    assert _inside_bin(placed[1], DEFAULT_MARGIN_M) and _apart(first, placed[1], 2 * DEFAULT_MARGIN_M)


def test_a_full_bin_fails_place_blocked_before_the_arm_moves() -> None:
    full = Detection("grey", (0, 0, 1, 1), (*BIN.center_xy_m, 0.02), (0.34, 0.22, 0.03), 0.0, 100, 1.0)
    robot = ContactRobot()
    q0 = robot.q.copy()
    statuses, tree = run('<PlaceIn fixture="bin"/>', robot,
                         {"grasp": GRASP, "target": HELD, "objects": (), "placed": (full,)})
    assert statuses == ["FAILURE"]
    values = tree.blackboard_values()
    assert values["failure_reason"] == "PLACE_BLOCKED"
    assert "no free spot in 'bin'" in tree.find("PlaceIn").feedback_message
    assert np.array_equal(robot.q, q0) and robot.target == 0.0


def test_place_in_needs_a_container_of_the_scene() -> None:
    from bt_grasp.behaviours.library import check_tree_against_scene
    from bt_grasp.errors import TreeFileError

    xml = '<root BTCPP_format="4"><BehaviorTree ID="T"><PlaceIn fixture="crate"/></BehaviorTree></root>'
    tree = load_tree_from_string(xml, robot_registry(), clock=ManualClock())
    with pytest.raises(TreeFileError, match="no fixture named 'crate'"):
        check_tree_against_scene(tree.nodes(), SCENE)


class HangingObjectRobot(ContactRobot):
    """The held object reaches 35 mm further than its perceived shape (off-centre and turned in the fingers, as a
    1 kg mug held by its side was): near a wall it meets the wall's top, so the tool stops 6 cm above the floor
    there; elsewhere it goes down as told."""

    def set_joint_targets(self, q_rad: Any, qd_rad_s: Any = None) -> None:
        T = KIN.fk(np.asarray(q_rad))
        dx = BIN.inner_size_m[0] / 2 - abs(T[0, 3] - BIN.center_xy_m[0])
        dy = BIN.inner_size_m[1] / 2 - abs(T[1, 3] - BIN.center_xy_m[1])
        # the object's 25 mm half-width, 20 mm of wall margin and 35 mm it hangs beyond both
        if min(dx, dy) < 0.025 + 0.035 and T[2, 3] < BIN.surface_z_m + 0.06:
            return
        self.q = np.asarray(q_rad, dtype=float)


def test_a_descent_that_met_something_early_makes_the_next_spot_one_with_room_round_it() -> None:
    # Tick by tick: PlaceIn chooses the best packed spot (against a wall), its descent stops 6 cm above the floor:
    # FAILURE PLACE_BLOCKED ("the descent met something"); Retreat backs off; the retry's PlaceIn, with the run's
    # memory of that descent and the same grip, grows its margins by 30 mm and chooses a spot with room round it:
    # SUCCESS. On main before this (the next best packed spot, against a wall again) every try met the wall.
    robot = HangingObjectRobot()
    body = ('<RetryUntilSuccessful num_attempts="3"><Fallback>'
            '<PlaceIn fixture="bin" grasp="{grasp}" held="{target}" objects="{objects}"/>'
            '<ForceFailure><Retreat height="0.05"/></ForceFailure>'
            '</Fallback></RetryUntilSuccessful>')
    statuses, tree = run(body, robot, {"grasp": GRASP, "target": HELD, "objects": ()}, ticks=8000)
    assert statuses[-1] == "SUCCESS", tree.find("PlaceIn").feedback_message
    place = [a for a in tree.find("PlaceIn").cell.attempts.attempts if a.kind.value == "place"]
    assert [(a.outcome.value, a.reason) for a in place] == [("BLOCKED", "PLACE_BLOCKED"), ("SUCCEEDED", None)]
    assert place[0].moved and place[1].moved
    room = [e for e in place[1].excluded if e.rule == "room"]
    assert len(room) == 1 and room[0].by == place[0].index and "30 mm more" in room[0].what
    (placed,) = tree.root_blackboard.get("placed")
    assert _inside_bin(placed, DEFAULT_WALL_MARGIN_M + 0.03)
