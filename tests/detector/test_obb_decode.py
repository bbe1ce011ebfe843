"""The decoder recovers crafted boxes exactly from a tiny ONNX model made here, and rotated NMS keeps what
Ultralytics keeps. Expected numbers are computed in the test from the formulas (probiou written out for the
shapes used), never by calling the code under test."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from bt_grasp.detector.letterbox import LetterboxGeometry
from bt_grasp.detector.model import ObbModel
from bt_grasp.detector.obb import batch_probiou, decode, nms_rotated

from .tiny_onnx import raw_output, write_model

NAMES = {0: "mug", 1: "banana", 2: "screwdriver"}
EPS = 1e-7
IMAGE = np.zeros((480, 640, 3), dtype=np.uint8)  # letterboxed into 320x320: gain 0.5, 40 px of grey on top


def _model(tmp_path: Path, rows, anchors: int = 16) -> ObbModel:
    path = write_model(tmp_path / "crafted.onnx", raw_output(rows, nc=3, anchors=anchors), names=NAMES,
                       imgsz=[320, 320])
    return ObbModel.load(path)


def _probiou_shifted_along_width(d: float, w: float) -> float:
    """Two equal boxes, the second moved by ``d`` along the first's width axis: the Gaussians share a covariance
    Sigma, so the Bhattacharyya distance is d^2 / (8 var_w) with var_w = w^2 / 12, i.e. 1.5 d^2 / w^2; probiou =
    1 - sqrt(1 - exp(-B)), with Ultralytics' eps = 1e-7 (B clamped from below by it, eps under the root)."""
    b = max(1.5 * d**2 / w**2, EPS)
    return 1 - math.sqrt(1 - math.exp(-b) + EPS)


def _probiou_crossed(w: float, h: float) -> float:
    """The same box at the same centre turned by 90 degrees: the summed covariance is (w^2 + h^2)/12 I, so
    B = 0.5 ln(((w^2 + h^2)/12)^2 / sqrt(det1 det2)) = 0.5 ln((w^2 + h^2)^2 / (4 w^2 h^2))."""
    b = 0.5 * math.log((w**2 + h**2) ** 2 / (4 * w**2 * h**2))
    return 1 - math.sqrt(1 - math.exp(-b) + EPS)


def test_decoder_recovers_the_crafted_boxes_exactly(tmp_path: Path) -> None:
    # input pixels (320x320); the original is (x - 0, y - 40) * 2
    rows = [
        (100.0, 115.0, 60.0, 20.0, 0.375, 1, 0.875),  # a banana, angle already in [0, pi/2)
        (250.0, 200.0, 30.0, 50.0, 2.0, 0, 0.75),  # a mug, angle 2.0 >= pi/2: w, h swap, angle 2.0 - pi/2
        (40.0, 260.0, 16.0, 8.0, -0.5, 2, 0.5),  # a screwdriver, angle -0.5: (-0.5 mod pi) >= pi/2 -> swap
        (150.0, 150.0, 10.0, 10.0, 0.0, 1, 0.25),  # exactly conf: not above 0.25, dropped as Ultralytics does
    ]
    found = _model(tmp_path, rows).detect(IMAGE)
    f32 = lambda v: float(np.float32(v))  # noqa: E731 - the tensor is float32
    expected = [
        # (cx, cy, w, h, angle, class, name, score) in original pixels
        (200.0, 150.0, 120.0, 40.0, f32(0.375), 1, "banana", f32(0.875)),
        (500.0, 320.0, 100.0, 60.0, f32(2.0) - math.pi / 2, 0, "mug", 0.75),
        (80.0, 440.0, 16.0, 32.0, f32(-0.5) % (math.pi / 2), 2, "screwdriver", 0.5),
    ]
    got = [(d.cx_px, d.cy_px, d.width_px, d.height_px, d.angle_rad, d.class_id, d.class_name, d.score)
           for d in found]
    assert len(got) == len(expected)
    for g, e in zip(got, expected, strict=True):
        assert g[:4] == e[:4]  # centre and size exact (gain 0.5 and pad 40 are exact in binary)
        assert g[4] == pytest.approx(e[4], abs=1e-12)
        assert g[5:] == e[5:]
    # the swapped mug is the same rectangle: its corners equal the unregularised box's
    mug = found[1]
    rect = cv2.boxPoints(((500.0, 320.0), (60.0, 100.0), math.degrees(f32(2.0))))
    np.testing.assert_allclose(sorted(map(tuple, mug.corners_px())), sorted(map(tuple, rect)), atol=1e-3)


def test_a_box_dropped_by_nms_still_drops_the_next_one(tmp_path: Path) -> None:
    """Fast-NMS as Ultralytics runs it: A suppresses B, and B (itself dropped) suppresses C although C does not
    overlap A enough. Greedy NMS would keep C; Ultralytics does not, and neither must we."""
    w, h, d = 100.0, 20.0, 20.0
    iou_ab = _probiou_shifted_along_width(d, w)
    iou_ac = _probiou_shifted_along_width(2 * d, w)
    assert iou_ab >= 0.7 > iou_ac  # the scenario is what it claims
    angle = 0.25
    ux, uy = math.cos(angle), math.sin(angle)
    rows = [
        (100.0, 150.0, w, h, angle, 0, 0.9),  # A
        (100.0 + d * ux, 150.0 + d * uy, w, h, angle, 0, 0.8),  # B: overlaps A
        (100.0 + 2 * d * ux, 150.0 + 2 * d * uy, w, h, angle, 0, 0.7),  # C: overlaps B, not A
        (100.0, 150.0, w, h, angle, 1, 0.6),  # A's twin of another class: class offset, never suppressed
        (100.0, 150.0, w, h, angle + math.pi / 2, 0, 0.65),  # A crossed at 90 degrees: low probiou, kept
    ]
    assert _probiou_crossed(w, h) < 0.7
    found = _model(tmp_path, rows).detect(IMAGE, iou=0.7)
    assert [(d.class_name, d.score) for d in found] == [("mug", pytest.approx(0.9)), ("mug", pytest.approx(0.65)),
                                                        ("banana", pytest.approx(0.6))]


def test_probiou_matches_the_formulas_and_sees_duplicates_opencv_keeps() -> None:
    angle = 0.6
    ux, uy = math.cos(angle), math.sin(angle)
    w, h = 100.0, 30.0
    a = np.array([[200.0, 200.0, w, h, angle]])
    for d in (0.0, 10.0, 24.0, 40.0):
        b = np.array([[200.0 + d * ux, 200.0 + d * uy, w, h, angle]])
        assert batch_probiou(a, b)[0, 0] == pytest.approx(_probiou_shifted_along_width(d, w), abs=1e-5)
    crossed = np.array([[200.0, 200.0, w, h, angle + math.pi / 2]])
    assert batch_probiou(a, crossed)[0, 0] == pytest.approx(_probiou_crossed(w, h), abs=1e-5)
    # shifted by 24 % of its length: polygon IoU 76/124 = 0.61, so OpenCV's NMSBoxesRotated at 0.7 keeps both;
    # probiou 0.71 >= 0.7, so Ultralytics (and we) keep one
    d = 24.0
    boxes = np.array([[200.0, 200.0, w, h, angle], [200.0 + d * ux, 200.0 + d * uy, w, h, angle]])
    scores = np.array([0.9, 0.8])
    assert _probiou_shifted_along_width(d, w) > 0.7
    assert nms_rotated(boxes, scores, 0.7).tolist() == [0]
    rects = [((float(x), float(y)), (float(bw), float(bh)), math.degrees(r)) for x, y, bw, bh, r in boxes]
    kept_by_opencv = cv2.dnn.NMSBoxesRotated(rects, scores.tolist(), 0.25, 0.7)
    assert len(kept_by_opencv) == 2


def test_nms_keeps_input_order_on_tied_scores_and_handles_no_boxes() -> None:
    boxes = np.array([[10.0, 10.0, 20.0, 5.0, 0.0], [200.0, 10.0, 20.0, 5.0, 0.0], [10.0, 10.0, 20.0, 5.0, 0.0]])
    assert nms_rotated(boxes, np.array([0.5, 0.5, 0.5]), 0.7).tolist() == [0, 1]
    assert nms_rotated(np.zeros((0, 5)), np.zeros(0), 0.7).tolist() == []


def test_decode_rejects_a_layout_that_does_not_fit_the_names() -> None:
    g = LetterboxGeometry.of((320, 320), (320, 320))
    with pytest.raises(ValueError, match=r"\[1, 8, anchors\]"):
        decode(np.zeros((1, 7, 10), np.float32), ("a", "b", "c"), g)


def test_detect_filters_by_class_name(tmp_path: Path) -> None:
    rows = [(100.0, 115.0, 60.0, 20.0, 0.375, 1, 0.875), (250.0, 200.0, 30.0, 50.0, 0.5, 0, 0.75)]
    model = _model(tmp_path, rows)
    assert [d.class_name for d in model.detect(IMAGE, classes=["mug"])] == ["mug"]
    assert model.info.input_hw == (320, 320) and model.names == ("mug", "banana", "screwdriver")
