"""Oriented boxes drawn the way a detector would draw them around the perception tests' synthetic objects, and
tiny ONNX models that "detect" them: the crafted output holds each box in the letterboxed input's pixels."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
from perception.perception_synth import DEFAULT_T_BASE_CAMERA, INTRINSICS, Box

from bt_grasp.detector.letterbox import LetterboxGeometry
from bt_grasp.detector.obb import OrientedDetection, regularize_rboxes
from bt_grasp.perception.learned import project

from .tiny_onnx import raw_output, write_model


def image_box(box: Box, name: str, score: float, grow: float = 1.1, turn_rad: float = 0.0,
              class_id: int = 0) -> OrientedDetection:
    """The oriented box a detector would draw around ``box`` (its 8 corners projected into the synthetic
    camera, ``cv2.minAreaRect``), grown by ``grow`` and turned by ``turn_rad`` in the image."""
    c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
    corners = [(box.centre_xy[0] + sx * box.size[0] / 2 * c - sy * box.size[1] / 2 * s,
                box.centre_xy[1] + sx * box.size[0] / 2 * s + sy * box.size[1] / 2 * c, z)
               for z in (0.0, box.size[2]) for sx in (-1, 1) for sy in (-1, 1)]
    px = project(np.array(corners), DEFAULT_T_BASE_CAMERA, INTRINSICS).astype(np.float32)
    (cx, cy), (w, h), angle = cv2.minAreaRect(px)
    b = regularize_rboxes(np.array([[cx, cy, w * grow, h * grow, math.radians(angle) + turn_rad]]))[0]
    return OrientedDetection(*(float(v) for v in b), class_id, name, score)


def model_seeing(path: Path, boxes: list[OrientedDetection], names: dict[int, str], imgsz: int = 320) -> Path:
    """A tiny model whose output is ``boxes`` (frame pixels of the 640x480 synthetic camera) in its input's
    pixels, whatever the picture."""
    geometry = LetterboxGeometry.of((INTRINSICS.height_px, INTRINSICS.width_px), (imgsz, imgsz))
    rows = []
    for b in boxes:
        cx, cy = geometry.to_input(np.array([b.cx_px, b.cy_px]))
        rows.append((float(cx), float(cy), b.width_px * geometry.gain, b.height_px * geometry.gain, b.angle_rad,
                     b.class_id, b.score))
    return write_model(path, raw_output(rows, nc=len(names)), names=names, input_shape=(1, 3, imgsz, imgsz))
