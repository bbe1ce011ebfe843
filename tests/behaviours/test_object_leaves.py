"""Object-query leaves tick by tick with stand-ins: PerceiveAll, SelectObject, ObjectPose, ObjectCount,
FixturePose (success and each failure reason)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.pose import Pose
from bt_grasp.clock import ManualClock
from bt_grasp.errors import TreeFileError
from bt_grasp.perception.results import Detection, PerceptionResult, PerceptionStatus
from bt_grasp.scene.format import Scene
from bt_grasp.tree.loader import load_tree_from_string


def det(label: str, x: float, y: float, size: tuple[float, float, float] = (0.05, 0.05, 0.05),
        shape: str = "box", yaw: float = 0.0) -> Detection:
    return Detection(label, (0, 0, 1, 1), (x, y, size[2] / 2), size, yaw, 100, 1.0, shape=shape)


RED = det("red", 0.50, 0.00)
BLUE_BIG = det("blue", 0.40, -0.20, (0.07, 0.04, 0.045))
GREEN_ROUND = det("green", 0.45, 0.22, (0.05, 0.05, 0.07), "round")
OBJECTS = (RED, BLUE_BIG, GREEN_ROUND)


def run(body: str, values: dict[str, Any] | None = None, scene: Scene | None = None) -> tuple[str, Any]:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    clock = ManualClock()
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    cell = fake_cell(FakeRobot(), clock)
    if scene is not None:
        cell.scene = scene
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in (values or {}).items():
        tree.root_blackboard.set(key, value)
    return tree.tick().value, tree


@pytest.mark.parametrize(
    ("attrs", "expected"),
    [
        ('color="blue"', BLUE_BIG),
        ('shape="round"', GREEN_ROUND),
        ('order="largest"', BLUE_BIG),
        ('order="smallest"', RED),
        ('order="nearest" point="0.45;0.2"', GREEN_ROUND),
        ('order="farthest" point="0.45;0.2"', BLUE_BIG),
        ('min_size="0.06"', BLUE_BIG),
        ('max_size="0.055" order="nearest" point="0.6;0"', RED),
    ],
)
def test_select_object_chooses_by_filter_and_order(attrs: str, expected: Detection) -> None:
    # one tick: SUCCESS and the chosen detection in {object}
    status, tree = run(f'<SelectObject objects="{{objects}}" {attrs} object="{{object}}"/>', {"objects": OBJECTS})
    assert status == "SUCCESS"
    assert tree.blackboard_values()["object"] is expected


def test_select_object_fails_no_detection_when_nothing_matches() -> None:
    status, tree = run('<SelectObject color="yellow"/>', {"objects": OBJECTS})
    assert status == "FAILURE"
    assert tree.blackboard_values()["failure_reason"] == "NO_DETECTION"
    assert "no yellow" in tree.find("SelectObject").feedback_message


def test_select_object_fails_bad_input_without_a_list() -> None:
    status, tree = run('<SelectObject/>', {"objects": "not a list"})
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


@pytest.mark.parametrize(("at", "offset", "z"), [("center", 0.0, 0.025), ("top", 0.0, 0.05), ("top", 0.1, 0.15),
                                                 ("bottom", 0.0, 0.0)])
def test_object_pose_at_centre_top_bottom_with_offset(at: str, offset: float, z: float) -> None:
    tilted = det("red", 0.5, 0.1, yaw=0.5)
    status, tree = run(f'<ObjectPose object="{{o}}" at="{at}" offset_z="{offset}" pose="{{p}}"/>', {"o": tilted})
    assert status == "SUCCESS"
    pose = tree.blackboard_values()["p"]
    assert isinstance(pose, Pose) and pose.frame == "base"
    assert (pose.x_m, pose.y_m) == (0.5, 0.1) and abs(pose.z_m - z) < 1e-12
    assert abs(pose.yaw_deg - 28.6478897565) < 1e-6


def test_object_pose_fails_bad_input() -> None:
    status, tree = run('<ObjectPose object="{o}"/>', {"o": 3})
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


@pytest.mark.parametrize(
    ("attrs", "status", "reason", "count"),
    [
        ("", "SUCCESS", None, 3),
        ('color="red" min="1" max="1"', "SUCCESS", None, 1),
        ('color="yellow"', "FAILURE", "NO_DETECTION", 0),
        ('min="0" max="2"', "FAILURE", "COUNT_EXCEEDED", 3),
        ('color="yellow" min="0"', "SUCCESS", None, 0),
    ],
)
def test_object_count(attrs: str, status: str, reason: str | None, count: int) -> None:
    got, tree = run(f'<ObjectCount objects="{{objects}}" {attrs} count="{{n}}"/>', {"objects": OBJECTS})
    values = tree.blackboard_values()
    assert got == status and values["n"] == count
    assert values.get("failure_reason") == reason


def _scene_with_tray() -> Scene:
    return Scene.model_validate({"version": 2, "robot": {"base_xyz_m": [0.0, 0.0, 0.0]}, "fixtures": [
        {"kind": "tray", "name": "left_tray", "center_xy_m": [0.4, 0.45], "yaw_deg": 10, "inner_size_m": [0.2, 0.2]},
    ]})


def test_fixture_pose_is_the_surface_centre_in_the_base_frame() -> None:
    status, tree = run('<FixturePose fixture="left_tray" pose="{p}"/>', scene=_scene_with_tray())
    assert status == "SUCCESS"
    pose = tree.blackboard_values()["p"]
    assert (pose.x_m, pose.y_m, pose.z_m, pose.yaw_deg) == pytest.approx((0.4, 0.45, 0.004, 10.0))


def test_fixture_pose_unknown_name_from_the_blackboard_fails_bad_input() -> None:
    status, tree = run('<FixturePose fixture="{name}"/>', {"name": "right_tray"}, scene=_scene_with_tray())
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"


def test_perceive_all_lists_every_object_and_an_empty_table_is_an_empty_list(monkeypatch: pytest.MonkeyPatch) -> None:
    from bt_grasp.behaviours import perceive

    results = iter([
        PerceptionResult(PerceptionStatus.OK, OBJECTS[:1], others=OBJECTS),
        PerceptionResult(PerceptionStatus.NO_OBJECTS),
    ])

    def fake_capture(leaf: Any, color: str | None, detector: Any = None) -> Any:
        return perceive.Captured(next(results), np.eye(4), 0, False)

    monkeypatch.setattr(perceive, "capture", fake_capture)
    status, tree = run('<PerceiveAll objects="{all}"/>')
    assert status == "SUCCESS" and tree.blackboard_values()["all"] == OBJECTS
    assert tree.tick().value == "SUCCESS" and tree.blackboard_values()["all"] == ()


def test_perceive_all_without_calibration_fails_calibration_missing() -> None:
    status, tree = run('<PerceiveAll/>')
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "CALIBRATION_MISSING"


@pytest.mark.parametrize("text", ["0.3", "0.3;x", "0.3;0.1;0;90;moon", "1;2;3;4;base;6", "0.3;;0.1", "nan;0"])
def test_a_malformed_pose_literal_is_a_load_error_naming_the_line(text: str) -> None:
    xml = ('<root BTCPP_format="4">\n<BehaviorTree ID="T">\n'
           f'<SelectObject order="nearest" point="{text}"/>\n</BehaviorTree>\n</root>')
    with pytest.raises(TreeFileError) as info:
        load_tree_from_string(xml, robot_registry(), clock=ManualClock())
    assert ":3:" in str(info.value) and "pose" in str(info.value), str(info.value)


def test_pose_text_round_trip_and_frames() -> None:
    assert Pose.from_port_text("0.35;-0.25") == Pose(0.35, -0.25)
    assert Pose.from_port_text(" 0.35; -0.25; 0.0; 90 ") == Pose(0.35, -0.25, 0.0, 90.0)
    world = Pose.from_port_text("0.35;-0.25;0.02;90;world")
    assert world.frame == "world" and Pose.from_port_text(world.to_port_text()) == world
    import numpy as np

    from bt_grasp.geometry import make_T, rot_z

    base = world.in_base(make_T(rot_z(np.pi / 2), [0.1, 0.0, 0.02]))
    assert (base.x_m, base.y_m, base.z_m, base.yaw_deg) == pytest.approx((-0.25, -0.25, 0.0, 0.0))
