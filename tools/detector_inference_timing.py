"""Per-frame cost of the learned detector on one thread: letterbox + network (onnxruntime) and decode + rotated
NMS, as ``bt_grasp.detector.inference.LearnedDetector.detect`` measures them, over N calls on one 640x480 frame.

    python tools/detector_inference_timing.py MODEL.onnx [--image color.png] [--calls 200] [--threads 1]

Without ``--image`` the frame is seeded noise (the network's cost does not depend on the picture; decode's
depends on how many boxes score above ``conf``: the count is printed). Times are wall-clock medians and p90 on
whatever load the machine has (the load average is printed beside them).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("--image", default=None, help="a colour picture (e.g. bt-grasp scene render's color.png)")
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    from bt_grasp.detector.inference import LearnedDetector

    if args.image:
        import cv2

        rgb = cv2.cvtColor(cv2.imread(args.image, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    else:
        rgb = np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8)
    detector = LearnedDetector.load(args.model, threads=args.threads)
    for _ in range(5):  # warm-up: the session's first runs allocate
        detector.detect(rgb)
    runs = [detector.detect(rgb) for _ in range(args.calls)]

    def stats(values: list[float]) -> dict[str, float]:
        return {"median": round(statistics.median(values), 2),
                "p90": round(float(np.quantile(values, 0.9)), 2)}

    print(json.dumps({
        "model": args.model, "input": list(detector.model.info.input_hw), "classes": len(detector.names),
        "threads": args.threads, "calls": args.calls, "boxes": len(runs[-1].boxes),
        "network_ms": stats([r.network_ms for r in runs]), "decode_ms": stats([r.decode_ms for r in runs]),
        "total_ms": stats([r.total_ms for r in runs]), "load_average": [round(v, 1) for v in os.getloadavg()],
    }))


if __name__ == "__main__":
    main()
