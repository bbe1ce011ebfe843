"""How perception takes a camera's exposure: a recording's colour pictures made darker and brighter, perceived again.

    python tools/realsense_exposure.py REC.db3 [REC.db3 ...] --calibration FILE [--detector learned]
                                       [--gains 0.5,0.7,1.0,1.4,2.0]

A real D435's colour imager settles its auto exposure over its first frames (bt_grasp skips them on a live device) and
follows the light after; the simulator's pictures are always exposed alike. Each gain multiplies every colour value
(clipped to 0-255) of each recorded frame, with its depth unchanged (the D435's depth comes from its infrared pair,
with its own exposure), and perceives it as ``perceive`` does; printed per gain: objects found, how many keep the
class (learned detector) and colour label they had at gain 1, and the largest centroid shift from gain 1.
docs/real-camera.md has the figures.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.hardware.realsense_open import open_recording
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception.results import Detection
from bt_grasp.sensing.open_source import open_source
from bt_grasp.sensing.perceive_frame import Perceiver
from bt_grasp.sensing.placement import Placement
from bt_grasp.sensing.source_spec import SourceSpec


def _objects(perceiver: Perceiver, frame: RGBDFrame, placement: Placement | None) -> tuple[Detection, ...]:
    return perceiver.perceive(frame, placement).result.others


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("recordings", nargs="+", type=Path)
    parser.add_argument("--calibration", type=Path, required=True)
    parser.add_argument("--detector", choices=[k.value for k in DetectorKind], default="learned")
    parser.add_argument("--gains", default="0.5,0.7,1.0,1.4,2.0")
    args = parser.parse_args()
    gains = [float(g) for g in args.gains.split(",")]
    totals = {g: [0, 0, 0, 0.0] for g in gains}  # objects, same class, same label, largest shift (mm)
    reference = 0
    for recording in args.recordings:
        opened = open_source(SourceSpec.recording(recording), args.calibration)
        opened.close()
        perceiver = Perceiver(opened.perception_config, opened.scene, DetectorKind(args.detector))
        with open_recording(recording) as camera:
            while (frame := camera.capture()) is not None:
                placement = opened.placer.place(frame, opened.perception_config)
                base = _objects(perceiver, frame, placement)
                reference += len(base)
                for gain in gains:
                    color = np.clip(np.round(frame.color.astype(np.float32) * gain), 0, 255).astype(np.uint8)
                    seen = _objects(perceiver, dataclasses.replace(frame, color=color), placement)
                    totals[gain][0] += len(seen)
                    for det in base:
                        near = min(seen, key=lambda d: float(np.linalg.norm(np.subtract(d.centroid_base_m,
                                                                                      det.centroid_base_m))),
                                   default=None)
                        if near is None:
                            continue
                        shift = 1000 * float(np.linalg.norm(np.subtract(near.centroid_base_m, det.centroid_base_m)))
                        totals[gain][1] += int(near.class_name == det.class_name)
                        totals[gain][2] += int(near.label == det.label)
                        totals[gain][3] = max(float(totals[gain][3]), shift)
    print(f"{reference} objects at gain 1 in {len(args.recordings)} recording(s), detector {args.detector}")
    print(f"{'gain':>5} {'objects':>8} {'same class':>11} {'same label':>11} {'largest shift mm':>17}")
    for gain, (count, same_class, same_label, shift) in totals.items():
        print(f"{gain:5.2f} {count:8d} {same_class:11d} {same_label:11d} {shift:17.2f}")


if __name__ == "__main__":
    main()
