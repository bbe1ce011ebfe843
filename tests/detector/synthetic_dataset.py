"""A tiny dataset in the layout `bt-grasp detector dataset` writes (images/, labels/, data.yaml), drawn with OpenCV
instead of rendered: seeded rotated bars (elongated) and blocks (square) on a grey floor, so training and
evaluation tests need no simulator."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from bt_grasp.detector.dataset import ObbLabel, data_yaml, label_lines

NAMES = ("bar", "block")
COLOURS = ((200, 40, 40), (40, 60, 200))  # RGB per class


def make_synthetic_dataset(out: Path, images: int, seed: int, size: int = 128) -> Path:
    rng = np.random.default_rng(seed)
    (out / "images").mkdir(parents=True, exist_ok=True)
    (out / "labels").mkdir(parents=True, exist_ok=True)
    for index in range(images):
        floor = int(rng.integers(90, 170))
        rgb = np.full((size, size, 3), floor, dtype=np.uint8)
        labels = []
        for class_id in (0, 1):
            cx, cy = (float(v) for v in rng.uniform(0.3 * size, 0.7 * size, 2))
            cx += (-0.18 if class_id == 0 else 0.18) * size  # bars on the left, blocks on the right: no overlap
            long_side = float(rng.uniform(0.30, 0.40)) * size
            w, h = (long_side, long_side / 3) if class_id == 0 else (long_side * 0.6, long_side * 0.6)
            angle = float(rng.uniform(0, 180))
            corners = cv2.boxPoints(((cx, cy), (w, h), angle)).astype(np.float64)
            cv2.fillPoly(rgb, [np.round(corners).astype(np.int32)], COLOURS[class_id])
            labels.append(ObbLabel(class_id, corners, int(w * h)))
        stem = f"{index:05d}"
        cv2.imwrite(str(out / "images" / f"{stem}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        (out / "labels" / f"{stem}.txt").write_text(label_lines(labels, size, size), encoding="utf-8")
    (out / "data.yaml").write_text(data_yaml(NAMES), encoding="utf-8")
    return out
