"""LoopObjects (BT.CPP's LoopNode over an object list) tick by tick with stand-ins, and ObjectInfo/FixturePose
slots: the data a "for every object" tree passes between leaves."""

from __future__ import annotations

from collections import deque
from typing import Any

import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.perception.results import Detection
from bt_grasp.scene.format import Scene
from bt_grasp.tree.loader import load_tree_from_string

RED = Detection("red", (0, 0, 1, 1), (0.5, 0.1, 0.025), (0.05, 0.05, 0.05), 0.0, 100, 1.0)
BLUE = Detection("blue", (0, 0, 1, 1), (0.5, -0.1, 0.02), (0.07, 0.04, 0.04), 0.0, 100, 1.0, shape="box")
GREEN = Detection("green", (0, 0, 1, 1), (0.4, 0.0, 0.035), (0.05, 0.05, 0.07), 0.0, 100, 1.0, shape="round")

LOOP = """
<root BTCPP_format="4"><BehaviorTree ID="T">
  <Sequence>
    <LoopObjects queue="{seen}" value="{item}" if_empty="{empty}">
      <Sequence>
        <ObjectInfo object="{item}" color="{c}" shape="{s}" size="{size}"/>
        <Script code="colours := colours + c + ';'"/>
        <ScriptCondition code="c != 'green'"/>
      </Sequence>
    </LoopObjects>
  </Sequence>
</BehaviorTree></root>
"""


def run(xml: str, values: dict[str, Any], ticks: int = 20, scene: Scene | None = None) -> tuple[list[str], Any]:
    clock = ManualClock()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = fake_cell(FakeRobot(), clock)
    if scene is not None:
        cell.scene = scene
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in values.items():
        tree.root_blackboard.set(key, value)
    statuses = []
    for _ in range(ticks):
        statuses.append(tree.tick().value)
        if statuses[-1] != "RUNNING":
            break
    return statuses, tree


def test_loop_visits_every_object_one_per_tick_then_succeeds() -> None:
    # tick 1: red (child SUCCESS -> loop RUNNING); tick 2: blue (RUNNING); tick 3: empty -> if_empty SUCCESS
    statuses, tree = run(LOOP, {"seen": (RED, BLUE), "colours": "", "empty": "SUCCESS"})
    assert statuses == ["RUNNING", "RUNNING", "SUCCESS"]
    values = tree.blackboard_values()
    assert values["colours"] == "red;blue;" and values["item"] is BLUE
    assert values["s"] == "box" and values["size"] == pytest.approx(0.07)


def test_loop_fails_when_the_child_fails_on_an_object() -> None:
    # tick 1: red ok (RUNNING); tick 2: green -> the condition fails -> loop FAILURE; blue never visited
    statuses, tree = run(LOOP, {"seen": (RED, GREEN, BLUE), "colours": "", "empty": "SUCCESS"})
    assert statuses == ["RUNNING", "FAILURE"]
    assert tree.blackboard_values()["colours"] == "red;green;"


def test_an_empty_list_returns_if_empty_at_once() -> None:
    assert run(LOOP, {"seen": (), "colours": "", "empty": "FAILURE"})[0] == ["FAILURE"]
    assert run(LOOP, {"seen": (), "colours": "", "empty": "SUCCESS"})[0] == ["SUCCESS"]


def test_a_shared_deque_is_popped_in_place() -> None:
    queue = deque([RED, BLUE])
    statuses, _ = run(LOOP, {"seen": queue, "colours": "", "empty": "SUCCESS"})
    assert statuses == ["RUNNING", "RUNNING", "SUCCESS"] and not queue


def test_a_list_of_something_else_is_a_runtime_error() -> None:
    from bt_grasp.tree.exceptions import TreeRuntimeError

    with pytest.raises(TreeRuntimeError, match="not a Detection"):
        run(LOOP, {"seen": ("red",), "colours": "", "empty": "SUCCESS"})


def test_object_info_without_an_object_fails_bad_input() -> None:
    xml = '<root BTCPP_format="4"><BehaviorTree ID="T"><ObjectInfo object="{o}"/></BehaviorTree></root>'
    statuses, tree = run(xml, {"o": None})
    assert statuses == ["FAILURE"] and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


def _tray_scene() -> Scene:
    return Scene.model_validate({"version": 2, "fixtures": [
        {"kind": "tray", "name": "tray", "center_xy_m": [0.3, 0.45], "inner_size_m": [0.22, 0.22]},
        {"kind": "marker", "name": "mark", "center_xy_m": [0.4, 0.0]},
    ]})


@pytest.mark.parametrize(("slot", "xy"), [(-1, (0.3, 0.45)), (0, (0.25, 0.40)), (1, (0.35, 0.40)),
                                          (2, (0.25, 0.50)), (3, (0.35, 0.50))])
def test_fixture_slots_fill_a_tray_row_by_row(slot: int, xy: tuple[float, float]) -> None:
    xml = ('<root BTCPP_format="4"><BehaviorTree ID="T">'
           f'<FixturePose fixture="tray" slot="{slot}" pose="{{p}}"/></BehaviorTree></root>')
    statuses, tree = run(xml, {}, scene=_tray_scene())
    pose = tree.blackboard_values()["p"]
    assert statuses == ["SUCCESS"] and (pose.x_m, pose.y_m) == pytest.approx(xy)


@pytest.mark.parametrize(("fixture", "slot", "fragment"), [("tray", 4, "has 4 slot(s)"), ("mark", 0, "no slots")])
def test_a_slot_that_does_not_exist_fails_bad_input(fixture: str, slot: int, fragment: str) -> None:
    xml = ('<root BTCPP_format="4"><BehaviorTree ID="T">'
           f'<FixturePose fixture="{fixture}" slot="{slot}"/></BehaviorTree></root>')
    statuses, tree = run(xml, {}, scene=_tray_scene())
    assert statuses == ["FAILURE"] and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"
    assert fragment in tree.find("FixturePose").feedback_message
