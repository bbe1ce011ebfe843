"""``perceive --log``: an MCAP log Foxglove shows whole, written with the project's own recorder (``RunRecorder``).

Per frame: the colour picture with its calibration and the detections' outlines on it, the aligned depth, the point
cloud (every k-th valid pixel, at most :data:`POINTS_MAX`), the detections as boxes, and each object's best grasps
drawn as grippers (``bt_grasp.recording.gripper_markers``), all in the output frame: ``base_link`` with a
calibration (``/tf``: ``world`` -> ``base_link`` -> ``camera_color_optical_frame``), the camera's optical frame
without one (``world`` is then the camera frame). Log time is the frames' device time from the first frame.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bt_grasp.geometry import Mat4
from bt_grasp.recording import topics
from bt_grasp.recording.gripper_markers import GripperMarker, gripper_update
from bt_grasp.recording.reproducible import log_epoch_ns
from bt_grasp.recording.schemas import BoxMarker
from bt_grasp.recording.writer import BASE_FRAME, CAMERA_FRAME, WORLD_FRAME, RunRecorder
from bt_grasp.sensing.perceive_frame import FramePerception
from bt_grasp.sensing.report import FrameReport

log = logging.getLogger(__name__)

POINTS_MAX = 20000
#: grasps drawn per object (the best few: a real object has dozens of sampled candidates)
GRASPS_DRAWN = 3
#: the log ends this long after its last frame (one frame period at 30 fps)
END_AFTER_NS = 33_333_333


class PerceiveLog:
    """One ``perceive`` run's log; frames are added with :meth:`add`, :meth:`close` finishes the file."""

    def __init__(self, path: str | Path, metadata: Mapping[str, str], T_world_base: Mat4 | None = None) -> None:
        self.path = Path(path)
        self._recorder = RunRecorder(self.path, metadata=metadata, time_origin_ns=log_epoch_ns(os.environ),
                                     handle_signals=False)
        self._T_world_base = np.eye(4) if T_world_base is None else np.asarray(T_world_base, dtype=float)
        self._first_stamp: int | None = None
        self._last_stamp = 0
        self._frames = 0

    def add(self, seen: FramePerception, report: FrameReport) -> None:
        frame, placement = seen.frame, seen.placement
        if self._first_stamp is None:
            self._first_stamp = frame.stamp_ns
        stamp = self._last_stamp = frame.stamp_ns - self._first_stamp
        self._frames += 1
        rec = self._recorder
        rec.write_color_image(stamp, frame.color, CAMERA_FRAME)
        rec.write_camera_calibration(stamp, CAMERA_FRAME, frame.intrinsics)
        rec.write_depth(stamp, frame.depth_m, CAMERA_FRAME)
        if placement is None:
            rec.write_log(stamp, "WARN", "perceive", f"frame {report.index}: {report.message}")
            return
        out = placement.frame_id
        T_out_camera = placement.T_out_camera
        if placement.calibrated:
            rec.write_transforms(stamp, [(WORLD_FRAME, BASE_FRAME, self._T_world_base),
                                         (BASE_FRAME, CAMERA_FRAME, T_out_camera)])
        else:
            rec.write_transforms(stamp, [(WORLD_FRAME, CAMERA_FRAME, np.eye(4))])
        # the detections' outlines on the picture: the recorder projects boxes given in its base frame through this
        rec.static_transforms[(BASE_FRAME, CAMERA_FRAME)] = T_out_camera
        self._points(stamp, seen, T_out_camera, out)
        boxes = [BoxMarker(f"object{o.index}", o.T_frame_box, o.size_m,
                           label=f"{o.index} {o.name} {o.confidence:.2f}") for o in report.objects]
        rec.write_markers(stamp, boxes, topic=topics.DETECTIONS, frame_id=out)
        grippers = [GripperMarker(f"object{o.index}_grasp{g.rank}", g.T_frame_tcp, g.width_m,
                                  float(np.linalg.norm(g.T_frame_pregrasp[:3, 3] - g.T_frame_tcp[:3, 3])), g.rank,
                                  f"{o.name} grasp {g.score:.2f}" if g.rank == 0 else "")
                    for o in report.objects for g in o.grasps[:GRASPS_DRAWN]]
        rec.write_scene(topics.GRASPS, stamp, gripper_update(rec.t(stamp), grippers, out))
        rec.write_log(stamp, "INFO", "perceive", f"frame {report.index}: {report.status}: {report.message}")

    def _points(self, stamp: int, seen: FramePerception, T_out_camera: Mat4, frame_id: str) -> None:
        # deferred: open3d (~1 s) only when a frame is perceived
        from bt_grasp.perception.cloud import depth_to_cloud, to_base

        frame = seen.frame
        valid = frame.depth_m > 0
        step = max(1, int(valid.sum()) // POINTS_MAX)
        if step > 1:
            keep = np.zeros(valid.size, dtype=bool)
            keep[np.flatnonzero(valid)[::step]] = True
            valid = keep.reshape(valid.shape)
        if not valid.any():
            return
        cloud = to_base(depth_to_cloud(frame.depth_m, frame.intrinsics, valid), T_out_camera)
        u, v = cloud.pixels[:, 0], cloud.pixels[:, 1]
        self._recorder.write_points(stamp, cloud.points.astype(np.float32), frame.color[v, u], frame_id)

    def dropped(self, index: int) -> None:
        self._recorder.write_log(self._last_stamp, "WARN", "perceive",
                                 f"frame {index}: no frame arrived (a dropped frame, or the recording's end)")

    def close(self) -> None:
        # the log's last message a frame period after its last frame: a log of one instant (one frame) is shown by
        # Foxglove 1.48 without its point cloud (measured: a one-frame log drew none; two frames, or this, drew it)
        self._recorder.write_log(self._last_stamp + END_AFTER_NS, "INFO", "perceive", f"{self._frames} frame(s)")
        self._recorder.flush_tick()
        self._recorder.close()
