"""The learned detector at tree level (issue 23), tick by tick with stand-ins and a tiny model the test builds
(no simulator, no training): PerceiveAll/Perceive with ``detector="learned"``, SelectObject by ``class``, the
``detector`` port's two values, and every bad input answered at load time in one sentence (exit 2)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell
from detector.synthetic_boxes import image_box, model_seeing
from detector.tiny_onnx import write_model
from perception.perception_synth import DEFAULT_T_BASE_CAMERA, Box, render

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.library import check_tree_against_scene
from bt_grasp.behaviours.objects import PerceiveAll, SelectObject, check_detector_classes
from bt_grasp.behaviours.perceive import Perceive
from bt_grasp.cli.main import main
from bt_grasp.clock import ManualClock
from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.detector.model import ModelError
from bt_grasp.errors import TreeFileError
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.scene.format import Scene
from bt_grasp.tree.formats.models import tree_nodes_model
from bt_grasp.tree.loader import LoadedTree, load_tree

NAMES = {0: "pen", 1: "box", 2: "mug"}
PEN = Box((0.45, 0.06), (0.14, 0.03, 0.04), math.radians(30.0))
CUBE = Box((0.50, -0.12), (0.05, 0.05, 0.05))
SCENE_BOXES = [image_box(PEN, "pen", 0.9, class_id=0), image_box(CUBE, "box", 0.6, class_id=1)]


class SynthCamera:
    mount = Mount.EYE_TO_HAND

    def __init__(self, frame: RGBDFrame) -> None:
        self.frame = frame

    def capture(self) -> RGBDFrame:
        return self.frame


class FixedCalibration:
    mount = "eye-to-hand"
    tool_link = "tool0"

    def T_base_camera_at(self, T_base_tool: np.ndarray | None = None) -> np.ndarray:
        return DEFAULT_T_BASE_CAMERA


def tree_file(folder: Path, body: str) -> Path:
    """``body`` as the only BehaviorTree of ``folder/t.xml``, its first node on line 3."""
    path = folder / "t.xml"
    path.write_text(f'<root BTCPP_format="4">\n<BehaviorTree ID="T">\n{body}\n</BehaviorTree>\n</root>\n')
    return path


def run(path: Path, values: dict[str, Any] | None = None) -> tuple[str, LoadedTree]:
    clock = ManualClock()
    tree = load_tree(path, robot_registry(), clock=clock)
    check_detector_classes(tree.nodes())
    cell = fake_cell(FakeRobot(), clock)
    cell.camera = SynthCamera(render([PEN, CUBE]))  # type: ignore[assignment]
    cell.calibration = FixedCalibration()
    for node in tree.nodes():
        node.setup(cell=cell)
    for key, value in (values or {}).items():
        tree.root_blackboard.set(key, value)
    return tree.tick().value, tree


PICK_BY_CLASS = ('<Sequence><PerceiveAll detector="learned" model="m.onnx" objects="{seen}"/>\n'
                 '<SelectObject objects="{seen}" class="{class}" object="{object}"/></Sequence>')


def test_perceive_all_names_objects_by_class_and_select_object_picks_one(tmp_path: Path) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)  # beside the tree file: a relative model path
    status, tree = run(tree_file(tmp_path, PICK_BY_CLASS), {"class": "box"})
    assert status == "SUCCESS"
    seen = tree.root_blackboard.get("seen")
    assert sorted((d.class_name, round(d.class_score, 6)) for d in seen) == [("box", 0.6), ("pen", 0.9)]
    chosen = tree.root_blackboard.get("object")
    assert chosen.class_name == "box" and chosen.centroid_base_m[:2] == pytest.approx(CUBE.centre_xy, abs=0.005)
    assert tree.find("SelectObject").feedback_message.startswith("box ")


def test_perceive_learned_targets_the_best_scoring_named_object(tmp_path: Path) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    body = '<Perceive detector="learned" model="m.onnx" target="{target}" objects="{objects}"/>'
    status, tree = run(tree_file(tmp_path, body))
    assert status == "SUCCESS"
    target = tree.root_blackboard.get("target")
    assert target.class_name == "pen" and math.degrees(target.yaw_rad) == pytest.approx(30.0, abs=1.5)
    assert len(tree.root_blackboard.get("objects")) == 2
    assert tree.find("Perceive").feedback_message.startswith("pen (0.90) ")


def test_a_class_no_object_has_is_no_detection_naming_the_classes_seen(tmp_path: Path) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    status, tree = run(tree_file(tmp_path, PICK_BY_CLASS), {"class": "mug"})
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "NO_DETECTION"
    assert tree.find("SelectObject").feedback_message == "no mug object among 2 object(s) (classes seen: box, pen)"


def test_a_class_asked_of_objects_no_learned_detector_named_is_no_detection(tmp_path: Path) -> None:
    body = ('<Sequence><PerceiveAll detector="{detector}" objects="{seen}"/>\n'
            '<SelectObject objects="{seen}" class="pen" object="{object}"/></Sequence>')
    status, tree = run(tree_file(tmp_path, body), {"detector": "geometric"})
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "NO_DETECTION"
    assert tree.find("SelectObject").feedback_message == (
        "no pen among 2 object(s): a learned detector named none of them (or they were perceived with the geometric "
        "detector)")


def test_the_detector_and_model_from_the_blackboard(tmp_path: Path) -> None:
    model = model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    body = ('<Sequence><PerceiveAll detector="{detector}" model="{model}" objects="{seen}"/>\n'
            '<SelectObject objects="{seen}" class="pen" object="{object}"/></Sequence>')
    status, tree = run(tree_file(tmp_path, body), {"detector": "learned", "model": str(model)})
    assert status == "SUCCESS" and tree.root_blackboard.get("object").class_name == "pen"
    status, tree = run(tree_file(tmp_path, body), {"detector": "yolo", "model": str(model)})
    assert status == "FAILURE" and tree.blackboard_values()["failure_reason"] == "BAD_INPUT"
    assert tree.find("PerceiveAll").feedback_message == "detector must be geometric or learned, not 'yolo'"
    with pytest.raises(ModelError, match=r"absent.onnx: no such model file"):
        run(tree_file(tmp_path, body), {"detector": "learned", "model": str(tmp_path / "absent.onnx")})


def test_the_detector_port_is_an_enum_with_geometric_the_default() -> None:
    for leaf in (Perceive, PerceiveAll):
        port = leaf.bt_spec.port("detector")  # type: ignore[attr-defined]
        assert port.choices == tuple(k.value for k in DetectorKind) == ("geometric", "learned")
        assert port.default == "geometric"
    models = tree_nodes_model([Perceive.bt_spec, PerceiveAll.bt_spec, SelectObject.bt_spec])  # type: ignore[attr-defined]
    assert models.count('<input_port name="detector" type="std::string" default="geometric">') == 2
    assert models.count('<input_port name="model" type="std::string" default="">') == 2
    assert '<input_port name="class" type="std::string" default="">' in models


# --- bad input: one sentence naming the tree file's line, at load time -------------------------------------

def _load_error(path: Path) -> str:
    with pytest.raises(TreeFileError) as info:
        tree = load_tree(path, robot_registry())
        check_tree_against_scene(tree.nodes(), Scene())
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}:")
    return message


def test_a_model_that_is_not_an_obb_export_is_a_load_error(tmp_path: Path) -> None:
    write_model(tmp_path / "m.onnx", np.zeros((1, 7, 16), np.float32), names=NAMES)  # 4 + 3: no angle channel
    message = _load_error(tree_file(tmp_path, PICK_BY_CLASS))
    assert message == (f"{tmp_path / 't.xml'}:3: PerceiveAll: port 'model': {tmp_path / 'm.onnx'}: is not a YOLO-OBB "
                       "export: its output [1, 7, 16] has no angle channel: a detection (not OBB) export for 3 classes")


def test_an_input_size_the_model_does_not_take_is_a_load_error(tmp_path: Path) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    body = '<PerceiveAll detector="learned" model="m.onnx" imgsz="640" objects="{seen}"/>'
    assert _load_error(tree_file(tmp_path, body)).endswith(
        "m.onnx: takes 320x320 images, not the 640x640 asked for (re-export it at that size)")


def test_a_missing_model_and_an_unknown_detector_are_load_errors(tmp_path: Path) -> None:
    body = '<PerceiveAll detector="learned" model="models/none.onnx" objects="{seen}"/>'
    assert _load_error(tree_file(tmp_path, body)).endswith(f"{tmp_path / 'models' / 'none.onnx'}: no such model file")
    body = '<PerceiveAll detector="yolo" objects="{seen}"/>'
    assert _load_error(tree_file(tmp_path, body)).endswith(
        "PerceiveAll: port 'detector' must be one of geometric, learned; got 'yolo'")


def test_a_class_the_model_does_not_have_is_a_load_error_with_did_you_mean(tmp_path: Path) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    body = PICK_BY_CLASS.replace('class="{class}"', 'class="pem"')
    message = _load_error(tree_file(tmp_path, body))
    assert message == (f"{tmp_path / 't.xml'}:4: SelectObject: port 'class': the model m.onnx has no class 'pem'; "
                       "did you mean 'pen'? (its classes: pen, box, mug)")


def test_a_class_in_a_tree_that_only_perceives_geometrically_is_a_load_error(tmp_path: Path) -> None:
    body = ('<Sequence><PerceiveAll objects="{seen}"/>\n'
            '<SelectObject objects="{seen}" class="mug" object="{o}"/></Sequence>')
    assert "every perceiving leaf of the tree uses the geometric detector" in _load_error(tree_file(tmp_path, body))


def test_tree_validate_answers_each_bad_input_in_one_sentence(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    model_seeing(tmp_path / "m.onnx", SCENE_BOXES, NAMES)
    good = tree_file(tmp_path, PICK_BY_CLASS.replace('class="{class}"', 'class="mug"'))
    assert main(["tree", "validate", str(good)]) == 0
    assert "OK (3 nodes" in capsys.readouterr().out
    bad = tree_file(tmp_path, PICK_BY_CLASS.replace('class="{class}"', 'class="Mug"'))
    assert main(["tree", "validate", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert re.search(r"t\.xml:4: SelectObject: port 'class': the model m\.onnx has no class 'Mug'; did you mean "
                     r"'mug'\?", err)
