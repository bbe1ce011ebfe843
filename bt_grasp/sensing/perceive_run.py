"""``perceive``: a source's frames through the pipeline, one report a frame, optionally an MCAP log.

``frames`` None reads a recording to its end; a live device or a scene gives ``default_frames`` (one) unless asked
for more. A frame that does not come is reported as dropped: a live device's next one is awaited, a recording that
ended before the frames asked for stops the run there.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import version
from pathlib import Path

from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.sensing.open_source import OpenedSource, open_source
from bt_grasp.sensing.perceive_frame import Perceiver
from bt_grasp.sensing.report import FrameReport, dropped_report, frame_report
from bt_grasp.sensing.source_spec import SourceKind, SourceSpec

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PerceiveRequest:
    source: SourceSpec
    calibration: Path | None = None
    detector: DetectorKind = DetectorKind.GEOMETRIC
    frames: int | None = None
    log: Path | None = None
    settings: RealSenseSettings = field(default_factory=RealSenseSettings)
    #: the run seed whose perception, grasp and IK streams the pipeline draws from (``bt_grasp.seeds``)
    seed: int = 0


@dataclass(frozen=True)
class PerceiveSummary:
    source: str
    frame_id: str
    calibrated: bool
    calibration: str
    detector: str
    reports: tuple[FrameReport, ...]
    log: Path | None

    def as_json(self) -> dict[str, object]:
        return {"source": self.source, "frame_id": self.frame_id, "calibrated": self.calibrated,
                "calibration": self.calibration, "detector": self.detector,
                "frames": [r.as_json() for r in self.reports], "log": str(self.log) if self.log else None}


def run_perceive(request: PerceiveRequest, on_frame: Callable[[FrameReport], None] | None = None
                 ) -> PerceiveSummary:
    """Perceive the request's frames (see the module docstring); ``on_frame`` is called with each report."""
    opened = open_source(request.source, request.calibration, request.settings)
    try:
        return _run(opened, request, on_frame)
    finally:
        opened.close()


def _run(opened: OpenedSource, request: PerceiveRequest, on_frame: Callable[[FrameReport], None] | None
         ) -> PerceiveSummary:
    perceiver = Perceiver(opened.perception_config, opened.scene, request.detector, seed=request.seed)
    frame_id = opened.placer.frame_id
    frames = request.frames if request.frames is not None else opened.default_frames
    writer = None
    if request.log is not None:
        # deferred: the MCAP writer only with --log
        from bt_grasp.sensing.perceive_log import PerceiveLog

        metadata = {"command": "perceive", "source": request.source.describe(), "frame_id": frame_id,
                    "calibration": str(request.calibration or opened.placer.calibration_path or ""),
                    "detector": request.detector.value, "bt_grasp_version": version("bt-grasp")}
        writer = PerceiveLog(request.log, metadata, opened.scene.T_world_base())
    reports: list[FrameReport] = []
    try:
        index = 0
        while frames is None or index < frames:
            frame = opened.camera.capture()
            if frame is None and frames is None:
                break  # a recording read to its end
            if frame is None:
                report = dropped_report(index, frame_id)
                if writer is not None:
                    writer.dropped(index)
            else:
                placement = opened.placer.place(frame, opened.perception_config)
                seen = perceiver.perceive(frame, placement)
                report = frame_report(index, seen)
                if writer is not None:
                    writer.add(seen, report)
            reports.append(report)
            if on_frame is not None:
                on_frame(report)
            index += 1
            if frame is None and request.source.kind is SourceKind.RECORDING:
                break  # the recording ended before the frames asked for
    finally:
        if writer is not None:
            writer.close()
    cal = opened.placer.calibration_path
    return PerceiveSummary(request.source.describe(), frame_id, opened.calibrated, str(cal or ""),
                           request.detector.value, tuple(reports), request.log)
