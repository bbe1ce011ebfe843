"""The cell file (``cells/*.yaml``): what bt-grasp must know about a work cell it does not simulate.

A cell file describes an installation, never its objects (they come from the camera): the arm and its controller's
address, the TCP and payload as the pendant has them, the speed caps every motion bt-grasp sends respects, the home
pose runs start from, the gripper (its model is what grasp synthesis and the planner's collision model use), the
camera (a RealSense by serial number, a recording, or a twin's camera) and its nominal mounting, the hand-eye
calibration file, the table top, the fixtures, the workspace box that perception and motion must stay in, and the
calibration board on the gripper. ``bt-grasp twin --write-cell`` writes one for the twin's cell; ``cells/`` holds
shipped examples. ``docs/real-cell.md`` explains each field.

Loaded strictly, like a scene file: an unknown key, a missing one or a wrong value is one sentence naming the file,
the line and the key. Version 2 (this one) is the first a run reads; version 1 (the twin's first cell files) is
refused with one sentence saying to write the file again.

Frames and units: every pose is in the robot's base frame (``base_link`` of bt_grasp's URDF: x forward, z up, origin
at the base's mounting face), metres and radians, a pose as UR's ``[x, y, z, rx, ry, rz]`` (a rotation vector) where
one is needed. The TCP is the flange-to-TCP offset as the controller's ``set_tcp`` takes it. The table top must be
horizontal in the base frame (the robot stands upright on or beside it): fixtures are placed by their ``x, y`` on it,
in the scene file's fixture format (``bt_grasp.scene.fixtures``), heights measured from the table top.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bt_grasp.errors import ConfigError
from bt_grasp.files.config import StrictModel, read_yaml, validate
from bt_grasp.scene.fixtures import Fixture

CELL_VERSION = 2

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Vec3 = tuple[float, float, float]
Pose = tuple[float, float, float, float, float, float]
Joints = tuple[float, float, float, float, float, float]
Range = tuple[float, float]
Host = Annotated[str, Field(min_length=1, max_length=253, pattern=r"^[A-Za-z0-9.:\-]+$")]
Port = Annotated[int, Field(ge=1, le=65535)]

#: the controller period of each arm model: ur_rtde runs RTDE at 125 Hz for a CB3 controller (a UR5)
CONTROL_RATE_HZ: dict[str, float] = {"ur5": 125.0}
#: the largest table tilt accepted (degrees): the table top must be horizontal in the base frame
MAX_TABLE_TILT_DEG = 2.0
#: the twin's camera port (frames for a run against the twin: ``bt_grasp.hardware.twin_camera``)
TWIN_CAMERA_PORT = 30101


def _ordered(lo_hi: Range, what: str) -> None:
    if not lo_hi[0] < lo_hi[1]:
        raise ValueError(f"{what} must be [low, high] with low below high, got {list(lo_hi)}")


class Arm(StrictModel):
    model: Literal["ur5"]
    address: Host  # where its controller listens (RTDE 30004, dashboard 29999, script 30003)
    tcp_pose: Pose  # the TCP in the flange frame (m, rad), as the pendant's / set_tcp's offset
    payload_kg: NonNegFloat
    payload_cog_m: Vec3  # in the flange frame
    #: where a run starts and ``MoveHome`` goes (rad); the first motion of a run goes here
    home_q_rad: Joints
    #: caps every motion bt-grasp sends respects (well under a UR5's 3.14 rad/s and 1 m/s: docs/real-cell.md)
    joint_speed_cap_rad_s: Annotated[float, Field(gt=0, le=3.14)] = 0.5
    joint_accel_cap_rad_s2: Annotated[float, Field(gt=0, le=40.0)] = 1.0
    tool_speed_cap_m_s: Annotated[float, Field(gt=0, le=1.0)] = 0.25

    @property
    def control_rate_hz(self) -> float:
        return CONTROL_RATE_HZ[self.model]


class Gripper(StrictModel):
    model: Literal["robotiq-2f85", "bt-grasp"]
    address: Host  # where the gripper's socket listens (the Robotiq URCap: the robot's address)
    port: Port = 63352
    stroke_m: PositiveFloat  # full opening between the pads
    pad_size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat]  # across, thickness, along the approach
    tcp_to_fingertip_m: NonNegFloat  # the finger tips lie this far beyond the TCP
    #: a request the gripper does not answer within this is a fault (the run ends GRIPPER_NOT_ANSWERING)
    answer_timeout_s: Annotated[float, Field(ge=0.02, le=5.0)] = 0.1


class EyeToHandMount(StrictModel):
    """Where a fixed camera nominally is (installation drawing, base frame): calibration plans its views from
    it; the calibration file says where it really is."""

    position_m: Vec3
    look_at_m: Vec3
    roll_deg: float = 0.0


class EyeInHandMount(StrictModel):
    """Where a wrist camera nominally is on its link (OpenCV optical axes, z forward)."""

    parent_link: Literal["tool0", "wrist_3_link"] = "tool0"
    xyz_m: Vec3
    rpy_deg: Vec3


class Camera(StrictModel):
    kind: Literal["twin", "realsense", "recording"]
    model: Literal["d435"] = "d435"
    mount: Literal["eye-to-hand", "eye-in-hand"]
    width_px: Annotated[int, Field(gt=0, le=4096)] = 640
    height_px: Annotated[int, Field(gt=0, le=4096)] = 480
    serial: Annotated[str, Field(pattern=r"^[0-9A-Za-z_\-]{1,64}$")] | None = None  # a RealSense's (kind realsense)
    path: str | None = None  # a recording, relative to the cell file (kind recording)
    address: Host | None = None  # the twin's address (kind twin)
    #: a delay added on the cell's clock after a frame's timestamp before its detections reach the tree, s; 0: none
    #: (a live camera's frames carry their real delay: the time perception takes passes on the wall clock)
    perception_latency_s: Annotated[float, Field(ge=0, le=2.0)] = 0.0
    port: Port = TWIN_CAMERA_PORT  # the twin's camera port (kind twin)
    eye_to_hand: EyeToHandMount | None = None
    eye_in_hand: EyeInHandMount | None = None

    @model_validator(mode="after")
    def _consistent(self) -> Camera:
        if self.kind == "twin" and self.address is None:
            raise ValueError("a twin's camera needs the twin's address")
        if self.kind == "recording" and self.path is None:
            raise ValueError("a recording camera needs the recording's path")
        if self.kind != "recording" and self.path is not None:
            raise ValueError(f"path is for kind recording, not {self.kind}")
        if self.kind != "realsense" and self.serial is not None:
            raise ValueError(f"serial is for kind realsense, not {self.kind}")
        nominal = self.eye_to_hand if self.mount == "eye-to-hand" else self.eye_in_hand
        if nominal is None:
            key = self.mount.replace("-", "_")
            raise ValueError(f"a {self.mount} camera needs its nominal mounting under {key}")
        return self


class TablePlane(StrictModel):
    """The table top: points p with ``normal . p = offset_m`` (base frame), spanning ``x_m`` by ``y_m``."""

    normal: Vec3
    offset_m: float
    x_m: Range
    y_m: Range

    @model_validator(mode="after")
    def _horizontal(self) -> TablePlane:
        norm = math.sqrt(sum(v * v for v in self.normal))
        if not norm > 0:
            raise ValueError("the normal must not be zero")
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, self.normal[2] / norm))))
        if tilt > MAX_TABLE_TILT_DEG:
            raise ValueError(f"the table top is tilted {tilt:.1f} degrees from the base frame's x-y plane; bt-grasp "
                             f"takes a horizontal table (within {MAX_TABLE_TILT_DEG:g} degrees)")
        _ordered(self.x_m, "x_m")
        _ordered(self.y_m, "y_m")
        return self

    @property
    def height_m(self) -> float:
        """The table top's height above the base frame's origin."""
        return self.offset_m / self.normal[2]  # the normal's z is not 0: the plane is horizontal


class WorkspaceBox(StrictModel):
    """The axis-aligned box (base frame) perception and motion must stay in. Perception looks for objects in it up
    to ``objects_up_to_m`` above the table top (the arm at its home pose must be above that: it is in view)."""

    min_m: Vec3
    max_m: Vec3
    objects_up_to_m: Annotated[float, Field(gt=0.0, le=2.0)] = 0.30

    @model_validator(mode="after")
    def _ordered(self) -> WorkspaceBox:
        if any(lo >= hi for lo, hi in zip(self.min_m, self.max_m, strict=True)):
            raise ValueError("every min_m coordinate must be below the max_m one")
        return self

    def contains(self, p: Vec3 | tuple[float, ...], margin_m: float = 0.0) -> bool:
        return all(lo - margin_m <= v <= hi + margin_m for v, lo, hi in zip(p, self.min_m, self.max_m, strict=True))


class Board(StrictModel):
    """The ChArUco board screwed to the gripper for calibration (eye-to-hand) or laid on the table (eye-in-hand):
    its layout and its nominal pose (``T_tool_board``, or ``T_base_board`` on the table) as a pose of its corner."""

    dictionary: Annotated[str, Field(pattern=r"^DICT_[0-9]+X[0-9]+_[0-9]+$")] = "DICT_5X5_100"
    squares_x: Annotated[int, Field(ge=3, le=30)] = 5
    squares_y: Annotated[int, Field(ge=3, le=30)] = 7
    square_m: Annotated[float, Field(gt=0.001, le=0.5)] = 0.035
    marker_m: Annotated[float, Field(gt=0.001, le=0.5)] = 0.026
    pose: Pose


class Cell(StrictModel):
    version: Literal[2]
    name: Annotated[str, Field(min_length=1, max_length=200)]
    arm: Arm
    gripper: Gripper
    camera: Camera
    calibration: str | None  # the hand-eye calibration file, relative to the cell file (None: not made yet)
    table_plane: TablePlane
    fixtures: tuple[Fixture, ...] = ()
    workspace: WorkspaceBox
    board: Board | None = None  # the calibration board (None: none mounted; `calibrate --cell` refuses)

    @model_validator(mode="after")
    def _fixtures_named_once(self) -> Cell:
        names = [f.name for f in self.fixtures]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"fixture names must be unique: {', '.join(twice)} appears more than once")
        return self


def load_cell(path: str | Path) -> Cell:
    """Load and validate a cell file; raises ConfigError naming the file, line and key."""
    data, lines = read_yaml(path)
    if isinstance(data, dict) and data.get("version") == 1:
        raise ConfigError(path, "is a version 1 cell file (written by an older `bt-grasp twin --write-cell`); it "
                          "lacks the home pose and the camera's mounting a run needs: write it again", where=lines.get(
                              ("version",)))
    return validate(Cell, data, path, lines)


def pose_to_T(pose: Pose) -> NDArray[np.float64]:
    """A UR pose ``[x, y, z, rx, ry, rz]`` (a rotation vector) as a 4x4 transform."""
    T = np.eye(4)
    rotvec = np.asarray(pose[3:], dtype=float)
    angle = float(np.linalg.norm(rotvec))
    if angle > 1e-12:
        k = rotvec / angle
        K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        T[:3, :3] = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
    T[:3, 3] = pose[:3]
    return T


def cell_file_path(cell_path: Path, relative: str) -> Path:
    """A file the cell file names (calibration, recording), relative to the cell file's folder."""
    return (Path(cell_path).parent / relative).resolve() if not Path(relative).is_absolute() else Path(relative)
