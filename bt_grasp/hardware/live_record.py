"""Recording a live RealSense device to a ``.db3`` with the library's own recorder (``config.enable_record_to_file``).

A live device's frames arrive in wall time, so this reads the wall clock: it records for ``seconds`` of it. The file is
written under a temporary name beside ``out`` and renamed when complete (an interrupted recording leaves nothing).
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_grasp.hardware.realsense_lib import pyrealsense2
from bt_grasp.hardware.realsense_open import start_device
from bt_grasp.hardware.realsense_settings import RealSenseSettings

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LiveRecording:
    path: Path
    serial: str
    frame_sets: int  # frame sets the pipeline handed out while recording
    seconds: float  # wall time recorded


def record_device(out: str | Path, seconds: float, serial: str | None = None,
                  settings: RealSenseSettings = RealSenseSettings(), context: Any = None) -> LiveRecording:
    """Record the device's depth and colour for ``seconds`` of wall time into ``out`` (a ``.db3``)."""
    rs = pyrealsense2("recording a live RealSense camera")
    context = context if context is not None else rs.context()
    out = Path(out)
    partial = out.with_name(f".{out.stem}.partial.db3")  # renamed once the recorder finished it
    with contextlib.suppress(FileNotFoundError):
        partial.unlink()
    pipeline, _profile, _device, chosen = start_device(context, serial, settings, record_to=partial)
    frame_sets = 0
    start = time.monotonic()
    try:
        while (left := seconds - (time.monotonic() - start)) > 0:
            ok, _frames = pipeline.try_wait_for_frames(max(1, min(int(left * 1000), settings.timeout_ms)))
            frame_sets += int(ok)
    except BaseException:
        pipeline.stop()
        with contextlib.suppress(FileNotFoundError):
            partial.unlink()
        raise
    pipeline.stop()  # the recorder finishes the file
    del pipeline, _profile, _device
    os.replace(partial, out)
    log.info("recorded %d frame sets of %s into %s", frame_sets, chosen, out)
    return LiveRecording(out, chosen, frame_sets, time.monotonic() - start)
