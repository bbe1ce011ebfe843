"""The robot description: one URDF that the simulator and the kinematics both load.

It is the UR5 of the ``example-robot-data`` wheel (BSD, from ros-industrial/universal_robot) with its
``package://`` mesh paths resolved to the installed files, the ROS ``world`` link dropped (the root is
``base_link``), and bt_grasp's own gripper (``bt_grasp/assets/gripper.urdf``) mounted on ``tool0``.
"""

from __future__ import annotations

import fcntl
import os
import sys
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from pathlib import Path
from xml.etree.ElementTree import Element, tostring

import defusedxml.ElementTree as SafeET

from bt_grasp.errors import BtGraspError

ARM_JOINTS: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
FINGER_JOINT = "left_finger_joint"  # the driven finger; right_finger_joint mimics it
MIMIC_FINGER_JOINT = "right_finger_joint"
BASE_LINK = "base_link"
TOOL_LINK = "tool0"
TCP_LINK = "tcp"
WRIST_CAMERA_LINK = "wrist_3_link"
GRIPPER_LINKS: tuple[str, ...] = ("gripper_palm", "left_finger", "right_finger")
#: the pad opening is twice the driven finger joint's position
MAX_OPENING_M = 0.085
#: distance from the tcp to the finger tips along the approach axis (tcp z)
TCP_TO_FINGERTIP_M = 0.02
#: adjacent or always-touching link pairs whose collisions are ignored (SRDF of the UR5 plus the gripper)
DISABLED_COLLISION_PAIRS: tuple[tuple[str, str], ...] = (
    ("base_link", "shoulder_link"),
    ("base_link", "upper_arm_link"),
    ("shoulder_link", "upper_arm_link"),
    ("upper_arm_link", "forearm_link"),
    ("forearm_link", "wrist_1_link"),
    ("forearm_link", "wrist_2_link"),
    ("forearm_link", "wrist_3_link"),
    ("wrist_1_link", "wrist_2_link"),
    ("wrist_1_link", "wrist_3_link"),
    ("wrist_2_link", "wrist_3_link"),
    ("wrist_3_link", "gripper_palm"),
    ("wrist_2_link", "gripper_palm"),
    ("wrist_3_link", "left_finger"),
    ("wrist_3_link", "right_finger"),
    ("gripper_palm", "left_finger"),
    ("gripper_palm", "right_finger"),
    ("left_finger", "right_finger"),
)


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of the UR5 arm, in joint order ``ARM_JOINTS``."""

    lower_rad: tuple[float, ...]
    upper_rad: tuple[float, ...]
    velocity_rad_s: tuple[float, ...]
    effort_nm: tuple[float, ...]


class RobotModelMissingError(BtGraspError):
    exit_code = 2


def ur_description_dir() -> Path:
    """The installed ``ur_description`` folder of the example-robot-data wheel."""
    for base in map(Path, sys.path):
        candidate = base / "cmeel.prefix/share/example-robot-data/robots/ur_description"
        if (candidate / "urdf/ur5_robot.urdf").is_file():
            return candidate
    raise RobotModelMissingError(
        "the UR5 model of example-robot-data is not installed; run `make setup` to install the package"
    )


def _gripper_urdf_text() -> str:
    return (files("bt_grasp") / "assets" / "gripper.urdf").read_text()


def _resolve_mesh(filename: str, share: Path) -> str:
    prefix = "package://example-robot-data/robots/ur_description/"
    if filename.startswith(prefix):
        return str(share / filename[len(prefix) :])
    return filename


def robot_urdf_text() -> str:
    """The merged URDF as text (deterministic for an installed model)."""
    share = ur_description_dir()
    robot = SafeET.fromstring((share / "urdf/ur5_robot.urdf").read_text())
    for child in list(robot):
        if (
            child.tag == "transmission"
            or child.tag == "gazebo"
            or (child.tag == "link" and child.get("name") == "world")
            or (child.tag == "joint" and child.get("name") == "world_joint")
        ):
            robot.remove(child)
    for mesh in robot.iter("mesh"):
        mesh.set("filename", _resolve_mesh(mesh.get("filename", ""), share))
    gripper = SafeET.fromstring(_gripper_urdf_text())
    for child in gripper:
        if isinstance(child, Element) and child.tag in ("link", "joint"):
            robot.append(child)
    robot.set("name", "ur5_bt_grasp")
    return '<?xml version="1.0"?>\n' + tostring(robot, encoding="unicode")


@cache
def robot_urdf_path() -> Path:
    """A path to the merged URDF that only this process can reach: an anonymous, sealed in-memory file
    (``memfd_create``) for the process's life, read through ``/proc/self/fd``. Nothing is written on disk and no
    cache is trusted: a file in a shared or working folder could be garbage, a FIFO or someone else's robot (with
    ``XDG_CACHE_HOME`` empty it was written to ``./bt_grasp/`` in the working folder, and a file found there was
    used as it was). A forked child inherits the descriptor, so the path works there too."""
    return sealed_urdf_path("ur5_bt_grasp.urdf", robot_urdf_text())


def sealed_urdf_path(name: str, text: str) -> Path:
    """``text`` as an anonymous, sealed in-memory file of this process (see :func:`robot_urdf_path`); cache the
    result: each call makes a new descriptor."""
    data = text.encode()
    fd = os.memfd_create(name, os.MFD_ALLOW_SEALING)  # not CLOEXEC: forked workers share it
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
    fcntl.fcntl(fd, fcntl.F_ADD_SEALS, fcntl.F_SEAL_SHRINK | fcntl.F_SEAL_GROW | fcntl.F_SEAL_WRITE | fcntl.F_SEAL_SEAL)
    return Path(f"/proc/self/fd/{fd}")


@cache
def arm_joint_limits() -> JointLimits:
    """Limits of the six arm joints, read from the URDF (one source of truth)."""
    robot = SafeET.fromstring(robot_urdf_text())
    by_name = {j.get("name"): j for j in robot.iter("joint")}
    lower, upper, vel, eff = [], [], [], []
    for name in ARM_JOINTS:
        limit = by_name[name].find("limit")
        assert limit is not None
        lower.append(float(limit.get("lower", "0")))
        upper.append(float(limit.get("upper", "0")))
        vel.append(float(limit.get("velocity", "0")))
        eff.append(float(limit.get("effort", "0")))
    return JointLimits(tuple(lower), tuple(upper), tuple(vel), tuple(eff))
