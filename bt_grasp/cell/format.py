"""The cell file (``cells/*.yaml``): what bt-grasp must know about a work cell it does not simulate.

A first, minimal version (``version: 1``), written by ``bt-grasp twin --write-cell`` for the twin's cell and
meant to grow with the real-cell work (issue 41). Loaded strictly, like a scene file: an unknown key, a missing
one or a wrong value is one sentence naming the file, the line and the key.

Frames and units: every pose is in the robot's base frame (``base_link`` of bt_grasp's URDF: x forward, z up,
origin at the base's mounting face), as a UR-style ``[x, y, z, rx, ry, rz]`` (metres, rotation vector in
radians) where a pose is needed. The TCP is the flange-to-TCP offset as the controller's ``set_tcp`` takes it.
There is no object list: objects come from the camera.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from bt_grasp.files.config import StrictModel, read_yaml, validate

CELL_VERSION = 1

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Vec3 = tuple[float, float, float]
Pose = tuple[float, float, float, float, float, float]
Host = Annotated[str, Field(min_length=1, max_length=253, pattern=r"^[A-Za-z0-9.:\-]+$")]
Port = Annotated[int, Field(ge=1, le=65535)]


class Arm(StrictModel):
    model: Literal["ur5"]
    address: Host  # where its controller listens (RTDE 30004, dashboard 29999, script 30003)
    tcp_pose: Pose  # the TCP in the flange frame (m, rad), as the pendant's / set_tcp's offset
    payload_kg: NonNegFloat
    payload_cog_m: Vec3  # in the flange frame
    #: caps every motion bt-grasp sends respects (well under a UR5's 3.14 rad/s and 1 m/s)
    joint_speed_cap_rad_s: Annotated[float, Field(gt=0, le=3.14)] = 0.5
    joint_accel_cap_rad_s2: Annotated[float, Field(gt=0, le=40.0)] = 1.0
    tool_speed_cap_m_s: Annotated[float, Field(gt=0, le=1.0)] = 0.25


class Gripper(StrictModel):
    model: Literal["robotiq-2f85", "bt-grasp"]
    address: Host  # where the gripper's socket listens (the Robotiq URCap: the robot's address)
    port: Port = 63352
    stroke_m: PositiveFloat  # full opening between the pads
    pad_size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat]  # across, thickness, along the approach
    tcp_to_fingertip_m: NonNegFloat  # the finger tips lie this far beyond the TCP


class Camera(StrictModel):
    kind: Literal["twin", "realsense", "recording"]
    model: Literal["d435"] = "d435"
    mount: Literal["eye-to-hand", "eye-in-hand"]
    width_px: Annotated[int, Field(gt=0, le=4096)] = 640
    height_px: Annotated[int, Field(gt=0, le=4096)] = 480
    serial: str | None = None  # a RealSense's serial number (kind realsense)
    path: str | None = None  # a recording, relative to the cell file (kind recording)
    address: Host | None = None  # the twin's address (kind twin)
    #: a delay added on the cell's clock after a frame's timestamp before its detections reach the tree, s; 0: none
    #: (a live camera's frames carry their real delay: the time perception takes passes on the wall clock)
    perception_latency_s: Annotated[float, Field(ge=0, le=2.0)] = 0.0


class Plane(StrictModel):
    """The table top: points p with ``normal . p = offset_m`` (base frame)."""

    normal: Vec3
    offset_m: float


class Box(StrictModel):
    size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat]  # full edge lengths along the box's axes
    pose: Pose  # the box centre's pose in the base frame
    solid: bool = True  # False: paint on the table (a marker), not an obstacle


class Fixture(StrictModel):
    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_\-]*$")]
    kind: str
    boxes: tuple[Box, ...]


class WorkspaceBox(StrictModel):
    """The axis-aligned box (base frame) perception and motion must stay in."""

    min_m: Vec3
    max_m: Vec3

    @model_validator(mode="after")
    def _ordered(self) -> WorkspaceBox:
        if any(lo >= hi for lo, hi in zip(self.min_m, self.max_m, strict=True)):
            raise ValueError("every min_m coordinate must be below the max_m one")
        return self


class Cell(StrictModel):
    version: Literal[1]
    name: Annotated[str, Field(min_length=1)]
    arm: Arm
    gripper: Gripper
    camera: Camera
    calibration: str | None  # the hand-eye calibration file, relative to the cell file (None: not made yet)
    table_plane: Plane
    fixtures: tuple[Fixture, ...] = ()
    workspace: WorkspaceBox


def load_cell(path: str | Path) -> Cell:
    """Load and validate a cell file; raises ConfigError naming the file, line and key."""
    data, lines = read_yaml(path)
    return validate(Cell, data, path, lines)
