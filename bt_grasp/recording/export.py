"""Export the recorded camera images as files: colour as PNG, depth as 16-bit PNG in millimetres."""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np

from bt_grasp.errors import InputError
from bt_grasp.files.output_files import make_output_folder, write_output_file
from bt_grasp.recording.reader import RunLog

log = logging.getLogger(__name__)


def _tick_of(stamps: list[tuple[int, int]], stamp_ns: int) -> int:
    """The last tick whose stamp is at or before ``stamp_ns`` (the first tick if none is)."""
    chosen = stamps[0][1] if stamps else 0
    for stamp, tick in stamps:
        if stamp > stamp_ns:
            break
        chosen = tick
    return chosen


def export_frames(run: RunLog, folder: str | Path) -> list[Path]:
    """Write every recorded colour image as ``color_<n>_tick<tick>.png`` and every depth image as
    ``depth_<n>_tick<tick>.png`` (uint16, millimetres, 0 = invalid) into ``folder``; returns the files."""
    out = make_output_folder(folder, "--export-frames")
    stamps = [(t.stamp_ns, t.tick) for t in run.ticks]
    written: list[Path] = []
    counters = {"color": 0, "depth": 0}
    for image in run.images():
        n = counters[image.kind]
        counters[image.kind] += 1
        target = out / f"{image.kind}_{n:05d}_tick{_tick_of(stamps, image.stamp_ns):06d}.png"
        if image.kind == "color":
            pixels = np.ascontiguousarray(image.pixels[:, :, ::-1])
        elif image.pixels.dtype == np.uint16:
            pixels = image.pixels
        else:
            mm = np.nan_to_num(image.pixels.astype(np.float64) * 1000.0, nan=0.0, posinf=0.0, neginf=0.0)
            pixels = np.clip(np.rint(mm), 0, 65535).astype(np.uint16)
        ok, png = cv2.imencode(".png", pixels)
        if not ok:
            raise InputError("--export-frames", f"could not encode {target.name} as PNG")
        written.append(write_output_file(target, png.tobytes(), "--export-frames"))
    log.debug("exported %d frames to %s", len(written), out)
    return written
