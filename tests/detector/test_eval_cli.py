"""`bt-grasp detector eval MODEL DATASET` runs a model through bt_grasp's own inference path (a crafted ONNX export
whose output is known) and scores it; bad input is exit 2 and one sentence. `detector train` without the training
extra says how to install it, and nothing in the runtime imports Ultralytics or torch."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from bt_grasp.cli.main import main
from bt_grasp.detector.dataset import ObbLabel, data_yaml, label_lines

from .tiny_onnx import raw_output, write_model

NAMES = ("mug", "banana", "pen")
# in a 320x320 picture (the model's input size: no letterbox), as the crafted model "sees" it
BANANA = (100.0, 120.0, 80.0, 24.0, 0.4)
MUG = (230.0, 200.0, 40.0, 40.0, 0.0)


def _corners(box: tuple[float, ...]) -> np.ndarray:
    cx, cy, w, h, r = box
    return cv2.boxPoints(((cx, cy), (w, h), np.degrees(r))).astype(np.float64)


def _dataset(folder: Path, names: tuple[str, ...] = NAMES) -> Path:
    (folder / "images").mkdir(parents=True)
    (folder / "labels").mkdir()
    cv2.imwrite(str(folder / "images" / "00000.png"), np.full((320, 320, 3), 128, np.uint8))
    labels = [ObbLabel(1, _corners(BANANA), 100), ObbLabel(0, _corners(MUG), 100)]
    (folder / "labels" / "00000.txt").write_text(label_lines(labels, 320, 320), encoding="utf-8")
    (folder / "data.yaml").write_text(data_yaml(names), encoding="utf-8")
    return folder


def _model(path: Path, rows: list[tuple[float, float, float, float, float, int, float]]) -> Path:
    return write_model(path, raw_output(rows, nc=3), names=dict(enumerate(NAMES)))


def _one_sentence(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("bt-grasp: error: ") and "\n" not in err and "Traceback" not in err, err
    return err


def test_eval_scores_what_the_inference_path_finds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = _dataset(tmp_path / "val")
    # the banana found 3 degrees off, the mug seen as a pen
    model = _model(tmp_path / "m.onnx", [(*BANANA[:4], BANANA[4] + np.radians(3.0), 1, 0.9), (*MUG, 2, 0.8)])
    assert main(["detector", "eval", str(model), str(data), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["images"] == 1 and report["labels"] == 2
    by_name = {c["name"]: c for c in report["per_class"]}
    assert by_name["banana"]["ap50"] == pytest.approx(0.995) and by_name["mug"]["ap50"] == 0.0
    assert report["map50"] == pytest.approx(0.995 / 2)  # mean over the classes with labels: banana, mug
    assert report["median_angle_error_deg"] == pytest.approx(3.0, abs=1e-3)
    matrix = report["confusion"]["matrix"]
    assert matrix[0][2] == 1 and matrix[1][1] == 1  # mug -> pen, banana -> banana
    assert main(["detector", "eval", str(model), str(data)]) == 0
    text = capsys.readouterr().out
    assert "mAP50 0.497" in text and "median angle error of elongated objects 3.0 deg" in text


def test_eval_bad_input_is_one_sentence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = _dataset(tmp_path / "val")
    model = _model(tmp_path / "m.onnx", [(*BANANA, 1, 0.9)])
    assert main(["detector", "eval", str(model), str(tmp_path / "absent")]) == 2
    assert "absent: no such dataset folder" in _one_sentence(capsys)
    assert main(["detector", "eval", str(model), str(tmp_path)]) == 2
    assert "is not a dataset: it has no data.yaml" in _one_sentence(capsys)
    detect = write_model(tmp_path / "detect.onnx", np.zeros((1, 7, 16), np.float32), names=dict(enumerate(NAMES)))
    assert main(["detector", "eval", str(detect), str(data)]) == 2
    assert "is not a YOLO-OBB export" in _one_sentence(capsys)
    other = _dataset(tmp_path / "other", names=("cup", "banana", "pen"))
    assert main(["detector", "eval", str(model), str(other)]) == 2
    err = _one_sentence(capsys)
    assert "m.onnx: its classes (mug, banana, pen) are not the dataset's" in err and "(cup, banana, pen)" in err
    (data / "labels" / "00000.txt").write_text("1 0.1 0.2 0.3\n", encoding="utf-8")
    assert main(["detector", "eval", str(model), str(data)]) == 2
    assert "00000.txt:1: expected 'class x1 y1 x2 y2 x3 y3 x4 y4', got 4 fields" in _one_sentence(capsys)


# Python run in a child process with ultralytics and torch made unimportable, as in an install without the extra
_WITHOUT_EXTRA = """
import sys, importlib.abc
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in ('ultralytics', 'torch', 'torchvision'):
            raise ModuleNotFoundError(f"No module named '{name}'", name=name)
        return None
sys.meta_path.insert(0, Block())
"""


def test_the_runtime_never_imports_the_training_extra() -> None:
    probe = _WITHOUT_EXTRA + (
        "import json, pkgutil, importlib, bt_grasp, bt_grasp.detector\n"
        "names = [m.name for m in pkgutil.iter_modules(bt_grasp.detector.__path__, 'bt_grasp.detector.')]\n"
        "for n in names + ['bt_grasp.cli.main', 'bt_grasp.cli.detector_cmd']: importlib.import_module(n)\n"
        "print(json.dumps([sorted(names), [m for m in ('ultralytics', 'torch') if m in sys.modules]]))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    modules, imported = json.loads(done.stdout.strip().splitlines()[-1])
    assert "bt_grasp.detector.train" in modules and "bt_grasp.detector.evaluate" in modules
    assert imported == []


def test_train_without_the_extra_says_how_to_install_it(tmp_path: Path) -> None:
    data = _dataset(tmp_path / "train")
    probe = _WITHOUT_EXTRA + (
        "from bt_grasp.cli.main import main\n"
        f"sys.exit(main(['detector', 'train', {str(data)!r}, '--out', {str(tmp_path / 'model')!r}]))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    err = done.stderr.strip()
    assert "\n" not in err and err.startswith("bt-grasp: error: bt-grasp detector train: needs the training extra")
    assert "pip install 'bt-grasp[train]'" in err


def _png_header(width: int, height: int) -> bytes:
    import struct
    import zlib

    ihdr = b"IHDR" + struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + ihdr + struct.pack(">I", zlib.crc32(ihdr))


@pytest.mark.parametrize(("damage", "fragment"), [
    ("bomb", "says it is 30000 x 30000 pixels, more than 8192 a side"),
    ("image_fifo", "is not a regular file"),
    ("label_fifo", "no such label file"),
    ("image_to_dev_zero", "is not a regular file"),
])
def test_hostile_dataset_files_are_one_sentence_never_a_hang(damage: str, fragment: str, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    """Found by the pre-review attack: dataset pictures were read by cv2.imread, unbounded: a FIFO picture hung
    `detector eval`, and a PNG of zeros saying 30,000 x 30,000 (under OpenCV's own 2^30-pixel limit) is decoded
    into 2.7 GB; now a picture is read bounded and its header checked first."""
    import os

    data = _dataset(tmp_path / "ds")
    image, label = data / "images" / "00000.png", data / "labels" / "00000.txt"
    if damage == "bomb":
        image.write_bytes(_png_header(30_000, 30_000))
    elif damage == "image_fifo":
        image.unlink()
        os.mkfifo(image)
    elif damage == "label_fifo":
        label.unlink()
        os.mkfifo(label)
    else:
        image.unlink()
        image.symlink_to("/dev/zero")
    model = _model(tmp_path / "m.onnx", [])
    assert main(["detector", "eval", str(model), str(data)]) == 2
    assert fragment in _one_sentence(capsys)
