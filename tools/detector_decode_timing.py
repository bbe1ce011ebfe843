"""Time the learned detector's numpy side on one thread: letterbox + input tensor of a 640x480 frame into 320x320,
and decode + rotated NMS of a synthetic 320-input output (2,100 anchors, 15 classes, 60 candidates above conf).
No network is run: this is the part bt_grasp adds to onnxruntime's own time.

    python tools/detector_decode_timing.py [--repeats 200]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import cv2
import numpy as np

from bt_grasp.detector.letterbox import LetterboxGeometry, letterbox, to_input_tensor
from bt_grasp.detector.obb import decode


def _time(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return float(np.median(samples)) * 1e3, float(np.percentile(samples, 90)) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=200)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    rng = np.random.default_rng(0)
    nc, anchors, hot = 15, 2100, 60
    out = np.zeros((1, 4 + nc + 1, anchors), np.float32)
    out[0, 0:2] = rng.uniform(0, 320, (2, anchors))
    out[0, 2:4] = rng.uniform(5, 80, (2, anchors))
    out[0, 4 : 4 + nc] = rng.uniform(0, 0.3, (nc, anchors)) ** 2
    out[0, 4, rng.choice(anchors, hot, replace=False)] = rng.uniform(0.3, 0.95, hot)
    out[0, -1] = rng.uniform(-0.78, 2.35, anchors)
    names = tuple(f"c{i}" for i in range(nc))
    geometry = LetterboxGeometry.of((480, 640), (320, 320))
    image = rng.integers(0, 255, (480, 640, 3), dtype=np.uint8)
    for label, fn in (("letterbox + input tensor", lambda: to_input_tensor(letterbox(image, (320, 320))[0])),
                      (f"decode + NMS ({hot} candidates)", lambda: decode(out, names, geometry))):
        median, p90 = _time(fn, args.repeats)
        print(f"{label}: median {median:.2f} ms, p90 {p90:.2f} ms")


if __name__ == "__main__":
    main()
