"""`bt-grasp detector train` end to end on a tiny drawn dataset (a dozen pictures, one epoch, 64 px), and the
shipped model's decoding checked against Ultralytics' own predictions on the same pictures.

Both need the `train` extra (ultralytics, torch, torchvision, onnxslim); where it is not installed they skip with
the reason printed in pytest's summary (`-ra`). They are not real-client tests: CI installs the `dev` extra only,
and the inference path they end in is tested in every install by test_eval_cli.py and test_model_checks.py.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import cv2
import numpy as np
import pytest

from bt_grasp.detector.evaluate import axis_error_deg, long_axis_rad
from bt_grasp.detector.model import ObbModel

from .synthetic_dataset import NAMES, make_synthetic_dataset

MISSING = [p for p in ("torch", "torchvision", "ultralytics", "onnxslim") if find_spec(p) is None]
needs_extra = pytest.mark.skipif(bool(MISSING), reason=f"the train extra is not installed (no {', '.join(MISSING)}):"
                                                       " pip install -e '.[train]'")
SHIPPED = Path(__file__).resolve().parents[2] / "bt_grasp" / "assets" / "detector" / "household_obb.onnx"
#: three held-out renders (`bt-grasp detector dataset ... --seed 1001`, pictures 0-2) as JPEG: both sides decode
#: the same pixels from them
PICTURES = Path(__file__).resolve().parents[1] / "data" / "detector"


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], capture_output=True, text=True,
                          cwd=cwd, env=env, timeout=900)


@needs_extra
@pytest.mark.slow
def test_tiny_training_end_to_end(tmp_path: Path) -> None:
    make_synthetic_dataset(tmp_path / "train", 12, seed=1)
    make_synthetic_dataset(tmp_path / "val", 4, seed=2)
    done = _cli("detector", "train", "train", "--val", "val", "--out", "model", "--name", "tiny", "--epochs", "1",
                "--imgsz", "64", "--batch", "4", "--seed", "3", "--threads", "1", cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    out = tmp_path / "model"
    model = ObbModel.load(out / "tiny.onnx", imgsz=64)  # bt_grasp's own checks accept the export as it is
    assert model.names == NAMES
    card = json.loads((out / "MODEL_CARD.json").read_text(encoding="utf-8"))
    assert card["classes"] == list(NAMES) and card["imgsz"] == 64 and card["epochs"] == 1 and card["seed"] == 3
    assert card["commands"]["train"].startswith("bt-grasp detector train train --val val --out model --name tiny")
    assert card["held_out"]["images"] == 4 and card["held_out"]["labels"] == 8
    assert 0.0 <= card["held_out"]["map50"] <= 1.0
    assert card["licences"]["weights"].startswith("AGPL-3.0")
    assert card["training_seconds"] > 0 and card["versions"]["ultralytics"]
    text = (out / "MODEL_CARD.md").read_text(encoding="utf-8")
    assert "AGPL-3.0" in text and "bt-grasp detector train train --val val" in text and "## Held-out figures" in text
    # offline: Ultralytics' settings and the font stand-in live in the run's own folder, not the home folder
    assert (out / "ultralytics" / "config" / "Ultralytics" / "Arial.ttf").is_file()
    assert (out / "ultralytics" / "weights" / "best.pt").is_file()
    evaluated = _cli("detector", "eval", "model/tiny.onnx", "val", "--json", cwd=tmp_path)
    assert evaluated.returncode == 0, evaluated.stderr[-2000:]
    report = json.loads(evaluated.stdout)
    assert report["map50"] == pytest.approx(card["held_out"]["map50"])
    assert report["confusion"]["labels"] == [*NAMES, "background"]


@needs_extra
@pytest.mark.skipif(not SHIPPED.is_file(), reason="no shipped model bt_grasp/assets/detector/household_obb.onnx")
def test_decoding_matches_ultralytics_own_predictions(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ultralytics' predictor running the same ONNX export (its letterbox, its NMS, its box scaling) against
    bt_grasp's ObbModel on held-out renders: the same boxes, classes and scores."""
    monkeypatch.setenv("YOLO_CONFIG_DIR", str(tmp_path))
    monkeypatch.setenv("YOLO_OFFLINE", "1")
    from ultralytics import YOLO

    ours = ObbModel.load(SHIPPED)
    theirs = YOLO(str(SHIPPED), task="obb")
    pictures = sorted(PICTURES.glob("*.jpg"))
    assert len(pictures) >= 3
    compared = 0
    for picture in pictures:
        bgr = cv2.imread(str(picture), cv2.IMREAD_COLOR)
        for conf in (0.25, 0.05, 0.002):
            found = ours.detect(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), conf=conf)
            result = theirs.predict(bgr, conf=conf, imgsz=ours.info.input_hw[0], verbose=False)[0]
            obb = result.obb
            expected = np.concatenate([obb.xywhr.numpy(), obb.cls.numpy()[:, None], obb.conf.numpy()[:, None]], 1)
            got = np.array([[d.cx_px, d.cy_px, d.width_px, d.height_px, d.angle_rad, d.class_id, d.score]
                            for d in found]).reshape(-1, 7)
            assert got.shape == expected.shape, (picture.name, conf)
            np.testing.assert_allclose(got[:, :2], expected[:, :2], atol=0.02)  # centres, pixels
            # the same rectangle: sides as a set, long axes parallel (an angle a hair below pi/2 in float64 can be
            # pi/2 in Ultralytics' float32, which then swaps w and h and wraps the angle to 0: same box)
            np.testing.assert_allclose(np.sort(got[:, 2:4], axis=1), np.sort(expected[:, 2:4], axis=1), atol=0.02)
            square = np.abs(got[:, 2] - got[:, 3]) < 0.5
            axes = axis_error_deg(long_axis_rad(got[:, :5]), long_axis_rad(expected[:, :5]))
            assert (axes[~square] < 0.01).all(), axes
            assert (got[:, 5] == expected[:, 5]).all()
            np.testing.assert_allclose(got[:, 6], expected[:, 6], atol=1e-5)
            compared += len(got)
    assert compared >= 10
