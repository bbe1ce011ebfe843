"""SelectObject and ObjectInfo over objects found by geometry (issue 28): by shape class, "any", a
two-coloured object's dominant colour, nearest to a fixture; tick by tick with stand-in detections."""

from __future__ import annotations

from typing import Any

import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.errors import TreeFileError
from bt_grasp.perception.results import Detection, ShapeClass
from bt_grasp.scene.format import Scene
from bt_grasp.tree.loader import load_tree_from_string


def det(label: str, x: float, y: float, shape_class: ShapeClass, size: tuple[float, float, float] = (0.05, 0.05, 0.05),
        color_name: str = "") -> Detection:
    return Detection(label, (0, 0, 1, 1), (x, y, size[2] / 2), size, 0.0, 100, 1.0, shape_class=shape_class,
                     color_name=color_name or label)


GREY_BOX = det("grey", 0.50, 0.00, ShapeClass.BOX_LIKE)
CAN = det("red", 0.42, 0.20, ShapeClass.CYLINDER_LIKE, (0.066, 0.066, 0.12))
PEN = det("black", 0.60, -0.12, ShapeClass.ELONGATED, (0.14, 0.012, 0.012))
PLATE = det("object", 0.62, 0.15, ShapeClass.FLAT, (0.16, 0.16, 0.015), color_name="white")
BRACKET = det("object", 0.40, -0.20, ShapeClass.OTHER, (0.08, 0.05, 0.04), color_name="orange")
OBJECTS = (GREY_BOX, CAN, PEN, PLATE, BRACKET)


def run(body: str, values: dict[str, Any], scene: Scene | None = None, ticks: int = 1) -> tuple[list[str], Any]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    clock = ManualClock()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = fake_cell(FakeRobot(), clock)
    if scene is not None:
        cell.scene = scene
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in values.items():
        tree.root_blackboard.set(key, value)
    return [tree.tick().value for _ in range(ticks)], tree


@pytest.mark.parametrize(
    ("attrs", "expected"),
    [
        ('shape_class="box-like"', GREY_BOX),
        ('shape_class="cylinder-like"', CAN),
        ('shape_class="elongated"', PEN),
        ('shape_class="flat"', PLATE),
        ('shape_class="other"', BRACKET),
        ('shape_class="any"', GREY_BOX),  # no filter: the first of the list
        ('color="any" shape="any" shape_class="any" order="farthest" point="0;0"', PLATE),
        ('shape_class="elongated" max_size="0.10"', None),  # the pen's 14 cm is longer
        ('color="white"', PLATE),  # the dominant colour, though too little of it made a label
        ('color="orange" shape_class="other"', BRACKET),
    ],
)
def test_select_object_by_shape_class_colour_and_any(attrs: str, expected: Detection | None) -> None:
    statuses, tree = run(f'<SelectObject objects="{{objects}}" {attrs} object="{{object}}"/>', {"objects": OBJECTS})
    values = tree.blackboard_values()
    if expected is None:
        assert statuses == ["FAILURE"] and values["failure_reason"] == "NO_DETECTION"
        assert "no elongated object among 5" in tree.find("SelectObject").feedback_message
    else:
        assert statuses == ["SUCCESS"] and values["object"] is expected


def test_select_object_nearest_to_a_fixture_through_fixture_pose() -> None:
    scene = Scene.model_validate({"version": 2, "robot": {"base_xyz_m": [0.0, 0.0, 0.0]}, "fixtures": [
        {"kind": "bin", "name": "bin", "center_xy_m": [0.35, 0.30], "inner_size_m": [0.2, 0.2]}]})
    body = ('<Sequence><FixturePose fixture="bin" pose="{bin}"/>'
            '<SelectObject objects="{objects}" order="nearest" point="{bin}" object="{object}"/></Sequence>')
    statuses, tree = run(body, {"objects": OBJECTS}, scene)
    assert statuses == ["SUCCESS"] and tree.blackboard_values()["object"] is CAN


def test_object_info_gives_the_shape_class() -> None:
    statuses, tree = run('<ObjectInfo object="{o}"/>', {"o": PEN})
    values = tree.blackboard_values()
    assert statuses == ["SUCCESS"] and values["object_shape_class"] == "elongated" and values["object_color"] == "black"


def test_an_unknown_shape_class_is_a_load_error() -> None:
    with pytest.raises(TreeFileError, match="shape_class"):
        run('<SelectObject shape_class="banana"/>', {"objects": OBJECTS})


def test_select_any_walks_every_object_whatever_it_is() -> None:
    # the clear-the-table loop: pick "any", drop it from the list, again, until none is left (one per tick)
    body = ('<Sequence><SelectObject objects="{left}" shape_class="any" object="{o}"/>'
            '<Script code="n += 1"/></Sequence>')
    statuses, tree = run(body, {"left": OBJECTS, "n": 0})
    assert statuses == ["SUCCESS"] and tree.blackboard_values()["o"] is GREY_BOX
    seen = []
    for k in range(len(OBJECTS)):
        tree.root_blackboard.set("left", OBJECTS[k:])
        assert tree.tick().value == "SUCCESS"
        seen.append(tree.blackboard_values()["o"])
    assert seen == list(OBJECTS)
    tree.root_blackboard.set("left", ())
    assert tree.tick().value == "FAILURE" and tree.blackboard_values()["failure_reason"] == "NO_DETECTION"
