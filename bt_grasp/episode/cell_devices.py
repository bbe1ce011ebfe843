"""Opening a real cell's devices from its cell file: the camera, the arm with its gripper, the safety guard, the clock.

Everything that can refuse runs before anything can move: the cell file's gripper is checked against the model
bt-grasp plans with (its TCP must be the arm's TCP: planning to one TCP while the controller moves another would put
the fingers where nothing was checked), the camera is opened (a twin's through its camera port, a RealSense by serial
number, or a recording), then the controller is connected (ur_rtde uploads its control script; the robot must be
powered, its brakes released, in remote control) and the gripper activated. Nothing is sent to the arm here.
:meth:`RealCell.close` stops the arm and lets every device go, in the reverse order.
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_grasp.cell.format import Cell, cell_file_path
from bt_grasp.cell.grippers import GRIPPERS, GripperModel, GripperName, robot_urdf_path_with
from bt_grasp.errors import InputError
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.hardware.robotiq_client import Robotiq2F85Client
from bt_grasp.hardware.ur_arm import UrArm
from bt_grasp.hardware.wall_time import CellStepper, MotionClock, WallClock
from bt_grasp.interfaces import Camera, Mount
from bt_grasp.motion.guard import GuardLimits, MotionGuard
from bt_grasp.motion.kinematics import ArmKinematics

log = logging.getLogger(__name__)

#: the cell's TCP may differ from the gripper model's by this much (m, rad) and still be the same TCP
TCP_TOLERANCE = 1e-4


@dataclass
class RealCell:
    """A real cell's open devices (see the module docstring)."""

    cell: Cell
    gripper_model: GripperModel
    kinematics: ArmKinematics
    guard: MotionGuard
    camera: Camera
    arm: UrArm
    clock: WallClock
    stepper: CellStepper
    close_camera: Callable[[], None]

    @property
    def motion_clock(self) -> MotionClock:
        return self.stepper.motion_clock

    def close(self) -> None:
        """Stop the arm (if it still takes commands), then let the arm, the gripper and the camera go."""
        with contextlib.suppress(Exception):
            self.arm.stop()
        self.arm.close()
        self.close_camera()


def gripper_model(cell: Cell, cell_path: Path) -> GripperModel:
    """The model bt-grasp plans with for the cell's gripper; InputError when the cell file disagrees with it."""
    model = GRIPPERS[GripperName(cell.gripper.model)]
    tcp = np.asarray(cell.arm.tcp_pose, dtype=float)
    expected = np.array([0.0, 0.0, model.tcp_z_m, 0.0, 0.0, 0.0])
    if float(np.max(np.abs(tcp - expected))) > TCP_TOLERANCE:
        raise InputError(cell_path, f"arm.tcp_pose {list(cell.arm.tcp_pose)} is not the TCP of the "
                         f"{model.name.value} gripper bt-grasp plans with ({expected.tolist()}): set the pendant's and "
                         "the cell file's TCP to it")
    g = cell.gripper
    if not (math.isclose(g.stroke_m, model.stroke_m, abs_tol=1e-4)
            and all(math.isclose(a, b, abs_tol=1e-4) for a, b in zip(g.pad_size_m, model.pad_size_m, strict=True))
            and math.isclose(g.tcp_to_fingertip_m, model.tcp_to_fingertip_m, abs_tol=1e-4)):
        raise InputError(cell_path, f"the gripper's stroke, pads or finger tips are not the {model.name.value}'s "
                         f"(stroke {model.stroke_m} m, pads {list(model.pad_size_m)} m, tips "
                         f"{model.tcp_to_fingertip_m} m beyond the TCP)")
    return model


def guard_for(cell: Cell, kinematics: ArmKinematics) -> MotionGuard:
    arm = cell.arm
    return MotionGuard(GuardLimits(
        joint_speed_cap_rad_s=arm.joint_speed_cap_rad_s, joint_accel_cap_rad_s2=arm.joint_accel_cap_rad_s2,
        tool_speed_cap_m_s=arm.tool_speed_cap_m_s, box_min_m=cell.workspace.min_m, box_max_m=cell.workspace.max_m,
        table_z_m=cell.table_plane.height_m, tcp_to_fingertip_m=cell.gripper.tcp_to_fingertip_m,
        period_s=1.0 / arm.control_rate_hz), kinematics)


def open_camera(cell: Cell, cell_path: Path, settings: RealSenseSettings) -> Camera:
    """The cell's camera (every kind is read through pyrealsense2); its ``close`` is ``camera.close``."""
    c = cell.camera
    mount = Mount(c.mount)
    if c.kind == "twin":
        # deferred: pyrealsense2 (through the twin's camera) only when a cell is opened
        from bt_grasp.hardware.twin_camera import TwinD435Camera

        assert c.address is not None
        return TwinD435Camera(c.address, c.port, settings)
    if c.kind == "recording":
        # deferred: as above
        from bt_grasp.hardware.realsense_open import open_recording

        assert c.path is not None
        return open_recording(cell_file_path(cell_path, c.path), settings, mount)
    # deferred: as above
    from bt_grasp.hardware.realsense_open import open_device

    sized = RealSenseSettings(width_px=c.width_px, height_px=c.height_px, fps=settings.fps,
                              timeout_ms=settings.timeout_ms, settle_frames=settings.settle_frames,
                              filters=settings.filters, preset=settings.preset)
    return open_device(c.serial, sized, mount)


def open_cell(cell: Cell, cell_path: Path, settings: RealSenseSettings = RealSenseSettings(),
              connect_arm: bool = True) -> RealCell:
    """Open the cell's devices (see the module docstring). ``connect_arm``: False opens the camera and checks only."""
    model = gripper_model(cell, cell_path)
    kinematics = ArmKinematics(urdf_path=robot_urdf_path_with(model.name))
    guard = guard_for(cell, kinematics)
    camera = open_camera(cell, cell_path, settings)
    close_camera: Callable[[], None] = getattr(camera, "close", lambda: None)
    g = cell.gripper
    lo, hi = model.force_range_n
    gripper = Robotiq2F85Client(g.address, g.port, g.stroke_m, (lo, hi if hi > lo else lo + 1.0), g.answer_timeout_s)
    arm = UrArm(cell.arm, gripper, guard)
    if connect_arm:
        try:
            arm.connect()
        except BaseException:
            arm.close()
            close_camera()
            raise
    clock = WallClock()
    stepper = CellStepper(clock, 1.0 / cell.arm.control_rate_hz, arm.poll)
    return RealCell(cell, model, kinematics, guard, camera, arm, clock, stepper, close_camera)


def describe(cell: Cell) -> dict[str, Any]:
    """Where a run on ``cell`` runs, for the log's metadata and the summary."""
    kind = "twin" if cell.camera.kind == "twin" else "robot"
    return {"ran_on": kind, "arm_address": cell.arm.address, "arm_model": cell.arm.model,
            "gripper": cell.gripper.model, "camera": cell.camera.kind}
