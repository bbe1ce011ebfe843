"""The inference path of the learned detector with a tiny model the test builds (no training, no simulator):
letterbox -> onnxruntime -> decode -> rotated NMS -> boxes in the frame's pixels, on one thread; and onnxruntime
stays out of every process that does not ask for a learned detector."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.detector.inference import LearnedDetector
from bt_grasp.detector.kinds import SHIPPED_MODEL, DetectorKind, model_path, parse_detector
from bt_grasp.detector.model import ModelError

from .tiny_onnx import raw_output, write_model

NAMES = {0: "mug", 1: "banana", 2: "screwdriver"}
REPO = Path(__file__).resolve().parents[2]


def test_boxes_come_back_in_the_frames_pixels_best_first(tmp_path: Path) -> None:
    # a 640x480 frame goes into 320x320 at gain 0.5, resized to 320x240, 40 px of grey above and below:
    # input (160, 160, 60 x 20) is the frame's (320, 240, 120 x 40); input (100, 60) is the frame's (200, 40)
    rows = [(160.0, 160.0, 60.0, 20.0, 0.375, 1, 0.875), (100.0, 60.0, 30.0, 30.0, 0.0, 0, 0.5),
            (161.0, 160.0, 60.0, 20.0, 0.375, 1, 0.25)]  # the third: not above conf (0.25), never a candidate
    path = write_model(tmp_path / "m.onnx", raw_output(rows, nc=3), names=NAMES)
    detector = LearnedDetector.load(path)
    found = detector.detect(np.zeros((480, 640, 3), dtype=np.uint8))
    assert [(b.class_name, b.score) for b in found.boxes] == [("banana", 0.875), ("mug", 0.5)]
    banana, mug = found.boxes
    assert (banana.cx_px, banana.cy_px, banana.width_px, banana.height_px) == pytest.approx((320, 240, 120, 40))
    assert banana.angle_rad == pytest.approx(0.375) and banana.long_axis_rad == pytest.approx(0.375)
    assert (mug.cx_px, mug.cy_px, mug.width_px) == pytest.approx((200, 40, 60))
    assert found.network_ms > 0 and found.decode_ms > 0 and found.total_ms == found.network_ms + found.decode_ms
    assert detector.names == ("mug", "banana", "screwdriver") and detector.path == path


def test_one_thread_by_default(tmp_path: Path) -> None:
    path = write_model(tmp_path / "m.onnx", raw_output([], nc=3), names=NAMES)
    session = LearnedDetector.load(path).model._session
    assert session.get_session_options().intra_op_num_threads == 1
    assert LearnedDetector.load(path, threads=2).model._session.get_session_options().intra_op_num_threads == 2


def test_overlapping_boxes_of_one_class_are_suppressed_not_of_two(tmp_path: Path) -> None:
    # equal 60 x 20 boxes shifted 2 px along their width: probabilistic IoU ~0.97 >= 0.7: one kept per class
    rows = [(160.0, 160.0, 60.0, 20.0, 0.0, 1, 0.9), (162.0, 160.0, 60.0, 20.0, 0.0, 1, 0.8),
            (162.0, 160.0, 60.0, 20.0, 0.0, 2, 0.7)]
    path = write_model(tmp_path / "m.onnx", raw_output(rows, nc=3), names=NAMES)
    found = LearnedDetector.load(path).detect(np.zeros((320, 320, 3), dtype=np.uint8))
    assert [(b.class_name, b.score) for b in found.boxes] == [("banana", pytest.approx(0.9)),
                                                             ("screwdriver", pytest.approx(0.7))]


def test_input_size_mismatch_and_unknown_class_are_one_sentence(tmp_path: Path) -> None:
    path = write_model(tmp_path / "m.onnx", raw_output([], nc=3), names=NAMES)
    with pytest.raises(ModelError, match=r"m.onnx: takes 320x320 images, not the 640x640 asked for"):
        LearnedDetector.load(path, imgsz=640)
    with pytest.raises(ModelError, match=r"has no class 'bananna'; did you mean 'banana'\? \(its classes: mug, "):
        LearnedDetector.load(path).class_id("bananna")


def test_detector_kinds_and_model_paths(tmp_path: Path) -> None:
    assert parse_detector("learned") is DetectorKind.LEARNED and parse_detector("") is DetectorKind.GEOMETRIC
    assert parse_detector("yolo") is None and [k.value for k in DetectorKind] == ["geometric", "learned"]
    assert model_path("", "trees/x.xml") == SHIPPED_MODEL
    assert model_path("m.onnx", tmp_path / "trees" / "x.xml") == tmp_path / "trees" / "m.onnx"
    assert model_path("m.onnx", None) == Path("m.onnx") and model_path("m.onnx", "<string>") == Path("m.onnx")
    assert model_path(str(tmp_path / "m.onnx"), "trees/x.xml") == tmp_path / "m.onnx"
    assert SHIPPED_MODEL == REPO / "bt_grasp" / "assets" / "detector" / "household_obb.onnx"


GEOMETRIC_RUN = r"""
import sys
sys.path.insert(0, {behaviours!r}); sys.path.insert(0, {perception!r})
from test_robot_leaves import _cell, _run, _tree
from perception_synth import Box, render
cell, robot, clock = _cell(render([Box((0.45, 0.0), (0.05, 0.05, 0.05))]))
tree = _tree('<Sequence><PerceiveAll objects="{{seen}}"/><Perceive detector="geometric" target="{{t}}" '
             'objects="{{o}}"/></Sequence>', cell, clock)
assert _run(tree, robot, clock) == ["SUCCESS"], tree.blackboard_values()
assert len(tree.root_blackboard.get("seen")) == 1
print(sorted(m for m in sys.modules if m.split(".")[0] in ("onnxruntime", "onnx")))
"""


def test_a_geometric_run_never_imports_onnxruntime() -> None:
    code = GEOMETRIC_RUN.format(behaviours=str(REPO / "tests" / "behaviours"),
                                perception=str(REPO / "tests" / "perception"))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, cwd=REPO,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_the_same_frame_gives_the_same_boxes(tmp_path: Path) -> None:
    rows = [(160.0 + k, 150.0 + 3 * k, 40.0 + k, 20.0, 0.1 * k, k % 3, 0.3 + 0.05 * k) for k in range(12)]
    path = write_model(tmp_path / "m.onnx", raw_output(rows, nc=3), names=NAMES)
    rgb = np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8)
    a = LearnedDetector.load(path).detect(rgb).boxes
    b = LearnedDetector.load(path).detect(rgb).boxes
    assert a == b and len(a) >= 2
    assert all(0 <= d.angle_rad < math.pi / 2 for d in a)


def test_bench_pick_takes_the_detector_as_a_typed_choice(capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.main import main

    assert main(["bench", "pick", "--detector", "yolo"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "'yolo'" in err and "geometric" in err and "learned" in err
