"""Where each frame is: in the robot's base frame (a calibration; a wrist camera's also the tool pose of the frame),
or, with no calibration, in the camera's own optical frame (``bt_grasp.perception.camera_frame``).

The pipeline always works in a frame whose z axis is the table's normal: the base frame, or the table frame the
frame itself shows. :class:`Placement` says which, and how results are given back in the output frame.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bt_grasp.errors import InputError
from bt_grasp.geometry import Mat4
from bt_grasp.hardware.tool_poses import ToolPose
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.perception.calibration_file import CalibrationFile, intrinsics_problem
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.robot_description import BASE_LINK

CAMERA_FRAME = "camera_color_optical_frame"


@dataclass(frozen=True)
class Placement:
    """One frame's placement.

    ``T_pipeline_camera`` is what :func:`bt_grasp.perception.pipeline.perceive` takes as ``T_base_camera`` (the base
    frame, or the table frame); ``T_out_pipeline`` maps the pipeline's results into ``frame_id``, the frame every
    output is given in (identity with a calibration); ``T_base_camera`` is the camera in the base frame (None
    without a calibration).
    """

    frame_id: str
    T_pipeline_camera: Mat4
    T_out_pipeline: Mat4
    T_base_camera: Mat4 | None

    @property
    def calibrated(self) -> bool:
        return self.T_base_camera is not None

    @property
    def T_out_camera(self) -> Mat4:
        return np.asarray(self.T_out_pipeline @ self.T_pipeline_camera, dtype=float)


class FramePlacer:
    """Places frames (see the module docstring). ``tool_pose(stamp_ns)``: the wrist camera's tool pose of a frame
    (None: no pose for it); ``poses_name``: what holds those poses, for the sentence when one is missing."""

    def __init__(self, calibration: CalibrationFile | None, calibration_path: Path | None,
                 tool_pose: Callable[[int], ToolPose | None] | None = None, poses_name: str = "") -> None:
        self.calibration = calibration
        self.calibration_path = calibration_path
        self._tool_pose = tool_pose
        self._poses_name = poses_name

    @property
    def frame_id(self) -> str:
        return BASE_LINK if self.calibration is not None else CAMERA_FRAME

    def check_source(self, intrinsics: CameraIntrinsics) -> None:
        """InputError when the calibration was made with other intrinsics than the source's."""
        if self.calibration is None:
            return
        problem = intrinsics_problem(self.calibration, intrinsics)
        if problem:
            raise InputError(self.calibration_path or "--calibration", f"does not fit this camera: {problem}")

    def place(self, frame: RGBDFrame, config: PerceptionConfig) -> Placement | None:
        """The frame's placement; None without a calibration when the frame shows no table plane."""
        identity = np.eye(4)
        calibration = self.calibration
        if calibration is None:
            # deferred: open3d (~1 s) only when a frame is perceived
            from bt_grasp.perception.camera_frame import pipeline_pose, table_frame

            T_camera_table = table_frame(frame, config)
            if T_camera_table is None:
                return None
            return Placement(CAMERA_FRAME, pipeline_pose(T_camera_table), T_camera_table, None)
        if Mount(calibration.mount) is Mount.EYE_TO_HAND:
            T = np.asarray(calibration.T_base_camera_at(None), dtype=float)
            return Placement(BASE_LINK, T, identity, T)
        pose = self._tool_pose(frame.stamp_ns) if self._tool_pose is not None else None
        if pose is None:
            raise InputError(self._poses_name or "tool poses", f"holds no tool pose stamped {frame.stamp_ns} ns, the "
                             "stamp of a frame of the recording (an eye-in-hand frame needs its tool pose)")
        if pose.child_frame != calibration.parent_frame:
            raise InputError(self._poses_name, f"its poses are of {pose.child_frame}, the calibration's camera is "
                             f"on {calibration.parent_frame}")
        T = np.asarray(calibration.T_base_camera_at(pose.T_base_tool), dtype=float)
        return Placement(BASE_LINK, T, identity, T)
