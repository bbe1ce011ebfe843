"""The twin's settings: which controller it pretends to be, where it listens, and its safety numbers."""

from __future__ import annotations

from dataclasses import dataclass

from bt_grasp.cell.format import TWIN_CAMERA_PORT
from bt_grasp.cell.grippers import GripperName
from bt_grasp.sim.twin.rtde_server import ControllerVersion

RTDE_PORT = 30004
DASHBOARD_PORT = 29999
SCRIPT_PORT = 30003  # the "secondary/real-time" script port ur_rtde uploads its control script to
GRIPPER_PORT = 63352  # the Robotiq URCap's socket
CONTROL_PORT = 30100  # the twin's own: faults, the judge, the camera (not a UR port)
CAMERA_PORT = TWIN_CAMERA_PORT  # the twin's own: camera frames for a run (not a UR port; bt_grasp.sim.twin.camera_port)


@dataclass(frozen=True)
class ControllerModel:
    """A controller the twin serves as: what RTDE and the dashboard report and the cycle it runs at."""

    name: str
    robot_model: str  # the dashboard's "get robot model"
    version: ControllerVersion  # RTDE's URControl version: ur_rtde picks 125 Hz for major 3, 500 Hz above
    software: str  # the dashboard's PolyscopeVersion line
    rate_hz: float
    serial_number: str


UR5_CB3 = ControllerModel(
    name="ur5", robot_model="UR5", version=ControllerVersion(3, 15, 7, 106331),
    software="URSoftware 3.15.7.106331 (Mar 10 2021)", rate_hz=125.0, serial_number="2015300042",
)
MODELS: dict[str, ControllerModel] = {m.name: m for m in (UR5_CB3,)}


@dataclass(frozen=True)
class TwinConfig:
    """How a twin runs. Times in seconds (wall clock: a twin runs in real time)."""

    host: str = "127.0.0.1"
    model: ControllerModel = UR5_CB3
    gripper: GripperName = GripperName.ROBOTIQ_2F85
    #: a UR controller refuses to unlock a protective stop sooner than this after it happened
    unlock_delay_s: float = 5.0
    #: a contact of the arm or gripper (not the pads on an object) pushing harder than this is a collision (N)
    collision_force_n: float = 150.0
    #: how fast the joints stop on a protective stop, a stopped program or a fired watchdog (rad/s^2)
    stop_decel_rad_s2: float = 10.0
    #: a message begun must be finished within this, on every port
    message_timeout_s: float = 5.0
    control_port: int = CONTROL_PORT
    camera_port: int = CAMERA_PORT
    #: the calibration board screwed to the gripper (``bt-grasp twin --board``), as for ``calibrate --cell``
    board: bool = False
    #: ask for real-time scheduling of the controller's cycle (SCHED_FIFO priority; None: do not ask)
    realtime_priority: int | None = 10

    @property
    def period_s(self) -> float:
        return 1.0 / self.model.rate_hz
