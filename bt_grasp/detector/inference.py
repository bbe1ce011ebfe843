"""Learned detection of one frame: letterbox -> network (onnxruntime, one thread by default) -> decode ->
rotated NMS -> oriented boxes in the frame's pixels with class and score, and what each step cost.

This module imports onnxruntime only through :meth:`LearnedDetector.load` (``ObbModel.load``): a tree that does
not ask for a learned detector never imports it. Times are measured with ``time.perf_counter`` for the record
(``PerceptionResult.timings_ms``) and never decide anything.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.model import DEFAULT_THREADS, ModelError, ObbModel
from bt_grasp.detector.obb import DEFAULT_CONF, DEFAULT_IOU, OrientedDetection, decode


@dataclass(frozen=True)
class FrameBoxes:
    """The oriented boxes found in one frame, best score first, and the time each step took (ms)."""

    boxes: tuple[OrientedDetection, ...]
    network_ms: float  # letterbox + the onnxruntime session
    decode_ms: float  # decoding, rotated NMS, mapping back to the frame's pixels

    @property
    def total_ms(self) -> float:
        return self.network_ms + self.decode_ms


class LearnedDetector:
    """A checked YOLO-OBB model and the thresholds it is decoded with (Ultralytics' defaults)."""

    def __init__(self, model: ObbModel, *, conf: float = DEFAULT_CONF, iou: float = DEFAULT_IOU) -> None:
        self.model = model
        self.conf = conf
        self.iou = iou

    @classmethod
    def load(cls, path: str | Path, *, imgsz: int | None = None, threads: int = DEFAULT_THREADS,
             conf: float = DEFAULT_CONF, iou: float = DEFAULT_IOU) -> LearnedDetector:
        """Open and check ``path`` (:class:`ModelError`, one sentence, when it is not a usable YOLO-OBB export
        or does not take ``imgsz`` images)."""
        return cls(ObbModel.load(path, imgsz=imgsz, threads=threads), conf=conf, iou=iou)

    @property
    def names(self) -> tuple[str, ...]:
        return self.model.names

    @property
    def path(self) -> Path:
        return self.model.info.path

    def class_id(self, name: str, source: str = "class") -> int:
        """The index of class ``name``; an unknown name is a :class:`ModelError` with a did-you-mean."""
        return self.model.class_id(name, source)

    def detect(self, rgb: NDArray[np.uint8]) -> FrameBoxes:
        """Oriented boxes in ``rgb``'s pixels (any size: it is letterboxed), best score first."""
        t0 = time.perf_counter()
        output, geometry = self.model.raw_output(np.ascontiguousarray(rgb[..., :3], dtype=np.uint8))
        t1 = time.perf_counter()
        if output.ndim != 3 or output.shape[1] != 4 + len(self.names) + 1:
            raise ModelError(self.path, f"produced an output of shape {list(output.shape)}, not "
                                        f"[1, {4 + len(self.names) + 1}, anchors]")
        boxes = decode(output, self.names, geometry, conf=self.conf, iou=self.iou)
        t2 = time.perf_counter()
        return FrameBoxes(tuple(boxes), (t1 - t0) * 1e3, (t2 - t1) * 1e3)
