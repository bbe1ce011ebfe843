"""The MediaSink that sends what leaves saw and computed to the run's MCAP recorder."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.attempts import Attempt
from bt_grasp.behaviours.services import TrajectoryKind
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception.results import GraspCandidate, PerceptionResult
from bt_grasp.recording.schemas import BoxMarker, PoseMarker
from bt_grasp.recording.writer import BASE_FRAME, CAMERA_FRAME, RunRecorder

_POINTS_MAX = 20000


class RecorderSink:
    """Implements :class:`bt_grasp.behaviours.services.MediaSink` on a :class:`RunRecorder`."""

    def __init__(self, recorder: RunRecorder, now_ns: Callable[[], int]) -> None:
        self.recorder = recorder
        self.now_ns = now_ns

    def frame(self, frame: RGBDFrame, T_base_camera: NDArray[np.float64] | None) -> None:
        stamp = self.now_ns()
        if T_base_camera is not None:  # the camera frame as this capture saw it (also for a later viewer)
            self.recorder.static_transforms[(BASE_FRAME, CAMERA_FRAME)] = np.asarray(T_base_camera, dtype=np.float64)
        if not self.recorder.active:  # a live view nobody watches: no encoding, no cloud until someone does
            self.recorder.when_watched("camera", lambda: self._write_frame(stamp, frame, T_base_camera))
            return
        self._write_frame(stamp, frame, T_base_camera)

    def _write_frame(self, stamp: int, frame: RGBDFrame, T_base_camera: NDArray[np.float64] | None) -> None:
        self.recorder.write_color_image(stamp, frame.color, CAMERA_FRAME)
        self.recorder.write_camera_calibration(stamp, CAMERA_FRAME, frame.intrinsics)
        self.recorder.write_depth(stamp, frame.depth_m, CAMERA_FRAME)
        if T_base_camera is not None:
            self.recorder.write_transforms(stamp, [(BASE_FRAME, CAMERA_FRAME, T_base_camera)])
            self._write_cloud(stamp, frame, T_base_camera)

    def _write_cloud(self, stamp: int, frame: RGBDFrame, T_base_camera: NDArray[np.float64]) -> None:
        from bt_grasp.perception.cloud import depth_to_cloud, to_base

        valid = frame.depth_m > 0
        step = max(1, int(valid.sum()) // _POINTS_MAX)
        if step > 1:  # keep every step-th valid pixel: a preview cloud, not the pipeline's
            keep = np.zeros(valid.size, dtype=bool)
            keep[np.flatnonzero(valid)[::step]] = True
            valid = keep.reshape(valid.shape)
        if not valid.any():
            return
        cloud = to_base(depth_to_cloud(frame.depth_m, frame.intrinsics, valid), T_base_camera)
        u, v = cloud.pixels[:, 0], cloud.pixels[:, 1]
        self.recorder.write_points(stamp, cloud.points.astype(np.float32), frame.color[v, u], BASE_FRAME)

    def perception(self, result: PerceptionResult, T_base_camera: NDArray[np.float64]) -> None:
        from bt_grasp.geometry import make_T, rot_z

        markers = []
        for i, det in enumerate(result.detections):
            T = make_T(rot_z(det.yaw_rad), np.asarray(det.centroid_base_m, dtype=float))
            markers.append(BoxMarker(f"det{i}", T, det.size_m, label=f"{det.label} {det.confidence:.2f}"))
        self.recorder.write_markers(self.now_ns(), markers, topic="/perception/detections")
        self.recorder.write_log(self.now_ns(), "INFO", "perception", f"{result.status.value}: {result.message}")

    def grasps(self, candidates: Sequence[GraspCandidate]) -> None:
        markers = [
            PoseMarker(f"grasp{i}", c.T_base_tcp_grasp, label=f"#{i} {c.score:.2f}") for i, c in enumerate(candidates)
        ]
        self.recorder.write_markers(self.now_ns(), markers, topic="/perception/grasps")

    def trajectory(self, name: str, times_s: NDArray[np.float64], q: NDArray[np.float64], kind: TrajectoryKind) -> None:
        self.recorder.write_trajectory(self.now_ns(), name, times_s, q, kind)

    def log(self, level: str, name: str, message: str) -> None:
        self.recorder.write_log(self.now_ns(), level, name, message)

    def servo(self, name: str, values: Mapping[str, float | bool | str]) -> None:
        self.recorder.write_event(self.now_ns(), "servo", {"leaf": name, **values})

    def attempt(self, attempt: Attempt) -> None:
        self.recorder.write_attempt(self.now_ns(), attempt.to_json())
