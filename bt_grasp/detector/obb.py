"""Decoding a YOLO-OBB export's raw output and rotated NMS, as Ultralytics' OBB predictor does it.

The export's output is ``[1, 4 + nc + 1, anchors]``: per anchor cx, cy, w, h (input pixels), ``nc`` class scores
already through a sigmoid, and the angle in radians. There is no NMS in the graph. Ultralytics then keeps each
anchor's best class when it scores above ``conf``, shifts boxes of different classes apart (class x 7680 px) so
they never suppress each other, and runs Fast-NMS with the probabilistic IoU of Gaussian boxes
(``batch_probiou``): sorted by score, a box is dropped when ANY higher-scoring box, kept or not, overlaps it by
``iou`` or more. That last rule differs from greedy NMS, and OpenCV's ``NMSBoxesRotated`` (polygon IoU) is a third
answer; the detector must keep what Ultralytics keeps. Boxes are then regularised (angle in [0, pi/2), w and h
swapped with it) and mapped back to the original image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.letterbox import LetterboxGeometry

#: Ultralytics' ``max_wh``: the class offset that keeps boxes of different classes apart in NMS
CLASS_OFFSET_PX = 7680.0
DEFAULT_CONF = 0.25
DEFAULT_IOU = 0.7  # Ultralytics' predict default
MAX_DETECTIONS = 300
MAX_NMS = 30000


@dataclass(frozen=True)
class OrientedDetection:
    """One detection in original-image pixels.

    ``angle_rad`` in [0, pi/2), measured from the image x axis toward y (down), the box's ``width_px`` side
    along it; ``class_id`` indexes the model's names; ``score`` is the class score (sigmoid) in (0, 1].
    """

    cx_px: float
    cy_px: float
    width_px: float
    height_px: float
    angle_rad: float
    class_id: int
    class_name: str
    score: float

    def corners_px(self) -> NDArray[np.float64]:
        """The 4 corners (4, 2) in Ultralytics' ``xywhr2xyxyxyxy`` order."""
        corners = xywhr_to_corners(np.array([[self.cx_px, self.cy_px, self.width_px, self.height_px, self.angle_rad]]))
        return np.asarray(corners[0], dtype=np.float64)

    @property
    def long_axis_rad(self) -> float:
        """Direction of the box's long side in the image, in [0, pi)."""
        return self.angle_rad if self.width_px >= self.height_px else (self.angle_rad + math.pi / 2) % math.pi


def xywhr_to_corners(boxes: NDArray[np.float64]) -> NDArray[np.float64]:
    """(N, 5) xywhr -> (N, 4, 2) corners, as Ultralytics' ``xywhr2xyxyxyxy``."""
    ctr = boxes[:, None, 0:2]
    w, h, r = boxes[:, 2:3], boxes[:, 3:4], boxes[:, 4:5]
    cos, sin = np.cos(r), np.sin(r)
    v1 = np.concatenate([w / 2 * cos, w / 2 * sin], axis=-1)[:, None]
    v2 = np.concatenate([-h / 2 * sin, h / 2 * cos], axis=-1)[:, None]
    return np.concatenate([ctr + v1 + v2, ctr + v1 - v2, ctr - v1 - v2, ctr - v1 + v2], axis=1)


def _covariance(boxes: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """Each box as a 2-D Gaussian (uniform box: variances w^2/12, h^2/12, rotated by r): (a, b, c) of
    [[a, c], [c, b]]."""
    a, b, r = boxes[:, 2] ** 2 / 12, boxes[:, 3] ** 2 / 12, boxes[:, 4]
    cos, sin = np.cos(r), np.sin(r)
    return a * cos**2 + b * sin**2, a * sin**2 + b * cos**2, (a - b) * cos * sin


def batch_probiou(obb1: NDArray[np.float64], obb2: NDArray[np.float64], eps: float = 1e-7) -> NDArray[np.float64]:
    """Probabilistic IoU (1 - Hellinger distance of the boxes' Gaussians, arXiv 2106.06072) of (N, 5) and (M, 5)
    xywhr boxes -> (N, M), with Ultralytics' epsilons and clamps."""
    x1, y1 = obb1[:, 0:1], obb1[:, 1:2]
    x2, y2 = obb2[None, :, 0], obb2[None, :, 1]
    a1, b1, c1 = (v[:, None] for v in _covariance(obb1))
    a2, b2, c2 = (v[None, :] for v in _covariance(obb2))
    den = (a1 + a2) * (b1 + b2) - (c1 + c2) ** 2 + eps
    t1 = ((a1 + a2) * (y1 - y2) ** 2 + (b1 + b2) * (x1 - x2) ** 2) / den * 0.25
    t2 = ((c1 + c2) * (x2 - x1) * (y1 - y2)) / den * 0.5
    det1 = np.clip(a1 * b1 - c1**2, 0, None)
    det2 = np.clip(a2 * b2 - c2**2, 0, None)
    t3 = np.log(((a1 + a2) * (b1 + b2) - (c1 + c2) ** 2) / (4 * np.sqrt(det1 * det2) + eps) + eps) * 0.5
    bd = np.clip(t1 + t2 + t3, eps, 100.0)
    hd = np.sqrt(1.0 - np.exp(-bd) + eps)
    return np.asarray(1.0 - hd, dtype=np.float64)


def nms_rotated(boxes: NDArray[np.float64], scores: NDArray[np.float64], iou: float) -> NDArray[np.intp]:
    """Fast-NMS by probabilistic IoU (Ultralytics' ``nms_rotated`` / ``TorchNMS.fast_nms``): indices of the kept
    boxes, best score first. A box is dropped when any higher-scoring box overlaps it by ``iou`` or more, even a
    box that was itself dropped. Ties in score keep the input order (a stable sort)."""
    if len(boxes) == 0:
        return np.empty((0,), dtype=np.intp)
    order = np.argsort(-scores, kind="stable")
    ious = np.triu(batch_probiou(boxes[order], boxes[order]), k=1)
    keep = (ious >= iou).sum(axis=0) <= 0
    return np.asarray(order[keep], dtype=np.intp)


def regularize_rboxes(boxes: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angle into [0, pi/2), w and h swapped when the angle mod pi is >= pi/2 (Ultralytics' ``regularize_rboxes``:
    the same rectangle, a canonical parameterisation)."""
    out = np.array(boxes, dtype=np.float64, copy=True)
    w, h, t = boxes[:, 2], boxes[:, 3], boxes[:, 4]
    swap = np.mod(t, math.pi) >= math.pi / 2
    out[:, 2] = np.where(swap, h, w)
    out[:, 3] = np.where(swap, w, h)
    out[:, 4] = np.mod(t, math.pi / 2)
    return out


def decode(
    output: NDArray[np.floating],
    names: tuple[str, ...],
    geometry: LetterboxGeometry,
    *,
    conf: float = DEFAULT_CONF,
    iou: float = DEFAULT_IOU,
    max_det: int = MAX_DETECTIONS,
) -> list[OrientedDetection]:
    """The raw ``[1, 4 + nc + 1, anchors]`` output -> detections in the original image, best score first.

    Raises ``ValueError`` when the layout does not match ``names`` (the model loader checks this first with a
    sentence for the user)."""
    nc = len(names)
    if output.ndim != 3 or output.shape[0] != 1 or output.shape[1] != 4 + nc + 1:
        raise ValueError(f"expected an output of shape [1, {4 + nc + 1}, anchors], got {list(output.shape)}")
    pred = np.asarray(output[0], dtype=np.float64).T  # (anchors, 4 + nc + 1)
    cls_scores = pred[:, 4 : 4 + nc]
    best = cls_scores.argmax(axis=1)
    score = cls_scores[np.arange(len(pred)), best]
    candidates = np.flatnonzero(score > conf)
    if len(candidates) > MAX_NMS:
        candidates = candidates[np.argsort(-score[candidates], kind="stable")[:MAX_NMS]]
    boxes = np.concatenate([pred[candidates, 0:4], pred[candidates, -1:]], axis=1)
    shifted = boxes.copy()
    shifted[:, 0:2] += best[candidates, None] * CLASS_OFFSET_PX
    kept = candidates[nms_rotated(shifted, score[candidates], iou)][:max_det]
    rboxes = regularize_rboxes(np.concatenate([pred[kept, 0:4], pred[kept, -1:]], axis=1))
    rboxes[:, 0:2] = geometry.to_original(rboxes[:, 0:2])
    rboxes[:, 2:4] /= geometry.gain
    return [
        OrientedDetection(float(b[0]), float(b[1]), float(b[2]), float(b[3]), float(b[4]), int(best[k]),
                          names[int(best[k])], float(score[k]))
        for b, k in zip(rboxes, kept, strict=True)
    ]
