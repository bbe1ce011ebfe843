"""Selectable grippers for the simulated cell: bt_grasp's own (every existing scene's) and a Robotiq 2F-85.

A model is its numbers (stroke, pads, TCP, speed and force ranges) and a URDF fragment with the link names every
part of bt_grasp knows (``gripper_palm``, ``left_finger``, ``right_finger``, ``tcp``), so the simulator, the
judge and a cell file all read one description. The 2F-85 here is a parallel-jaw approximation of the real,
linkage-driven gripper: its 85 mm stroke, its fingertip pads (22 x 6.35 x 37.5 mm, the ROS-Industrial
``robotiq_arg2f`` description's pad), its 20-150 mm/s and 20-235 N ranges and its TCP 174.5 mm from the
flange (the fingertips' centre, Robotiq's figure for the UR coupling); the fingers move straight, not on the real
gripper's arc (about 10 mm of vertical travel over the stroke), and the body is one box.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from xml.etree.ElementTree import Element, tostring

import defusedxml.ElementTree as SafeET
import numpy as np
from numpy.typing import NDArray

from bt_grasp.robot_description import (
    GRIPPER_LINKS,
    MAX_OPENING_M,
    TCP_LINK,
    robot_urdf_path,
    robot_urdf_text,
    sealed_urdf_path,
)


class GripperName(enum.StrEnum):
    BT_GRASP = "bt-grasp"
    ROBOTIQ_2F85 = "robotiq-2f85"


@dataclass(frozen=True)
class GripperModel:
    """A parallel-jaw gripper as planning and serving both need it (metres, newtons, seconds)."""

    name: GripperName
    stroke_m: float  # full opening between the pads
    pad_size_m: tuple[float, float, float]  # pad box: across the closing direction, thickness, along the approach
    tcp_z_m: float  # the TCP's distance from the tool flange along the approach axis
    tcp_to_fingertip_m: float  # the finger tips lie this far beyond the TCP
    mass_kg: float
    speed_range_m_s: tuple[float, float]  # opening speed (Robotiq's SPE 0..255)
    force_range_n: tuple[float, float]  # grip force (Robotiq's FOR 0..255)
    palm_above_tcp_m: float = 0.040  # the underside of the gripper's body lies this far above the TCP


BT_GRASP = GripperModel(
    name=GripperName.BT_GRASP, stroke_m=MAX_OPENING_M, pad_size_m=(0.02, 0.012, 0.055), tcp_z_m=0.08,
    tcp_to_fingertip_m=0.02, mass_kg=0.4, speed_range_m_s=(0.3, 0.3), force_range_n=(40.0, 40.0),
)
ROBOTIQ_2F85 = GripperModel(
    name=GripperName.ROBOTIQ_2F85, stroke_m=0.085, pad_size_m=(0.022, 0.00635, 0.0375), tcp_z_m=0.1745,
    tcp_to_fingertip_m=0.02, mass_kg=0.925, speed_range_m_s=(0.020, 0.150), force_range_n=(20.0, 235.0),
    palm_above_tcp_m=round(0.1745 - 0.125, 4),  # the body box reaches 0.125 m from the flange (below)
)
GRIPPERS: dict[GripperName, GripperModel] = {g.name: g for g in (BT_GRASP, ROBOTIQ_2F85)}


@dataclass(frozen=True)
class BoardLayout:
    """A ChArUco board's layout (the default is the one ``bt-grasp calibrate`` uses: 5 x 7 squares of 35 mm)."""

    dictionary: str = "DICT_5X5_100"
    squares_x: int = 5
    squares_y: int = 7
    square_m: float = 0.035
    marker_m: float = 0.026

    @property
    def size_m(self) -> tuple[float, float]:
        return self.squares_x * self.square_m, self.squares_y * self.square_m

    def as_dict(self) -> dict[str, str | int | float]:
        return {"dictionary": self.dictionary, "squares_x": self.squares_x, "squares_y": self.squares_y,
                "square_m": self.square_m, "marker_m": self.marker_m}


#: a board screwed to a gripper stands this far beyond its finger tips (clear of the fingers)
BOARD_BEYOND_TIPS_M = 0.01


def board_standoff_m(gripper: GripperModel) -> float:
    """How far from the flange a calibration board on ``gripper`` stands (bt_grasp's own: 0.11 m, as always)."""
    return round(gripper.tcp_z_m + gripper.tcp_to_fingertip_m + BOARD_BEYOND_TIPS_M, 6)


def T_tool_board(gripper: GripperModel, layout: BoardLayout) -> NDArray[np.float64]:
    """The board's corner frame on ``tool0``: centred on the tool axis at :func:`board_standoff_m`, its printed side
    facing away from the flange (board z = -tool z)."""
    R = np.diag([1.0, -1.0, -1.0])
    width, height = layout.size_m
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.array([0.0, 0.0, board_standoff_m(gripper)]) - R @ np.array([width / 2, height / 2, 0.0])
    return T

# --- the 2F-85 as URDF (metres) --------------------------------------------------------------------------
_PAD_W, _PAD_T, _PAD_L = ROBOTIQ_2F85.pad_size_m
_TIP_Z = ROBOTIQ_2F85.tcp_z_m + ROBOTIQ_2F85.tcp_to_fingertip_m  # finger tips from the flange
_JOINT_Z = _TIP_Z - _PAD_L  # the prismatic joints sit at the pads' top edge
_BODY = (0.06, 0.11, 0.125)  # the body box (coupling included), flange to z = 0.125
_FINGER_BAR = (0.022, 0.012, _JOINT_Z - _BODY[2] - 0.002)  # above each pad, clear of the body


def _box_inertia(mass: float, size: tuple[float, float, float]) -> str:
    x, y, z = size
    return (f'ixx="{mass * (y * y + z * z) / 12:.7f}" ixy="0" ixz="0" iyy="{mass * (x * x + z * z) / 12:.7f}" '
            f'iyz="0" izz="{mass * (x * x + y * y) / 12:.7f}"')


def _finger(side: str, sign: int) -> str:
    pad_y = sign * _PAD_T / 2
    bar_y = sign * (_PAD_T + _FINGER_BAR[1] / 2)
    bar_z = -_FINGER_BAR[2] / 2 - 0.001
    return f"""
  <link name="{side}_finger">
    <inertial><origin xyz="0 {pad_y:.5f} {_PAD_L / 2:.5f}"/><mass value="0.06"/>
      <inertia {_box_inertia(0.06, (_PAD_W, _PAD_T + _FINGER_BAR[1], _PAD_L + _FINGER_BAR[2]))}/></inertial>
    <visual><origin xyz="0 {pad_y:.5f} {_PAD_L / 2:.5f}"/><geometry><box size="{_PAD_W} {_PAD_T} {_PAD_L}"/></geometry>
      <material name="pad_black"><color rgba="0.08 0.08 0.08 1"/></material></visual>
    <collision><origin xyz="0 {pad_y:.5f} {_PAD_L / 2:.5f}"/>
      <geometry><box size="{_PAD_W} {_PAD_T} {_PAD_L}"/></geometry></collision>
    <visual><origin xyz="0 {bar_y:.5f} {bar_z:.5f}"/>
      <geometry><box size="{_FINGER_BAR[0]} {_FINGER_BAR[1]} {_FINGER_BAR[2]:.5f}"/></geometry>
      <material name="finger_grey"><color rgba="0.3 0.3 0.32 1"/></material></visual>
    <collision><origin xyz="0 {bar_y:.5f} {bar_z:.5f}"/>
      <geometry><box size="{_FINGER_BAR[0]} {_FINGER_BAR[1]} {_FINGER_BAR[2]:.5f}"/></geometry></collision>
  </link>
  <joint name="{side}_finger_joint" type="prismatic">
    <parent link="gripper_palm"/><child link="{side}_finger"/>
    <origin xyz="0 0 {_JOINT_Z:.5f}" rpy="0 0 0"/><axis xyz="0 {sign} 0"/>
    <limit lower="0.0" upper="{ROBOTIQ_2F85.stroke_m / 2}" effort="235.0" velocity="0.075"/>
    {'<mimic joint="left_finger_joint" multiplier="1" offset="0"/>' if side == "right" else ""}
  </joint>"""


ROBOTIQ_2F85_URDF = f"""<?xml version="1.0"?>
<!-- A Robotiq 2F-85 as a parallel jaw (bt_grasp.cell.grippers says what is approximated). -->
<robot name="robotiq_2f85">
  <link name="gripper_palm">
    <inertial><origin xyz="0 0 {_BODY[2] / 2}"/><mass value="0.8"/><inertia {_box_inertia(0.8, _BODY)}/></inertial>
    <visual><origin xyz="0 0 {_BODY[2] / 2}"/><geometry><box size="{_BODY[0]} {_BODY[1]} {_BODY[2]}"/></geometry>
      <material name="body_grey"><color rgba="0.2 0.2 0.22 1"/></material></visual>
    <collision><origin xyz="0 0 {_BODY[2] / 2}"/><geometry><box size="{_BODY[0]} {_BODY[1]} {_BODY[2]}"/></geometry>
    </collision>
  </link>
  <joint name="gripper_mount_joint" type="fixed">
    <parent link="tool0"/><child link="gripper_palm"/><origin xyz="0 0 0" rpy="0 0 0"/>
  </joint>{_finger("left", 1)}{_finger("right", -1)}
  <link name="tcp"/>
  <joint name="tcp_joint" type="fixed">
    <parent link="gripper_palm"/><child link="tcp"/><origin xyz="0 0 {ROBOTIQ_2F85.tcp_z_m}" rpy="0 0 0"/>
  </joint>
</robot>
"""

_GRIPPER_PARTS = {*GRIPPER_LINKS, TCP_LINK}


def robot_urdf_with(gripper: GripperName) -> str:
    """The merged robot URDF with ``gripper`` on the flange (bt-grasp's is the default, unchanged, text)."""
    text = robot_urdf_text()
    if gripper == GripperName.BT_GRASP:
        return text
    robot = SafeET.fromstring(text)
    for child in list(robot):
        if (child.tag == "link" and child.get("name") in _GRIPPER_PARTS) or (
            child.tag == "joint" and (child.find("child") is not None)
            and child.find("child").get("link") in _GRIPPER_PARTS
        ):
            robot.remove(child)
    for child in SafeET.fromstring(ROBOTIQ_2F85_URDF):
        if isinstance(child, Element) and child.tag in ("link", "joint"):
            robot.append(child)
    return '<?xml version="1.0"?>\n' + tostring(robot, encoding="unicode")


@cache
def robot_urdf_path_with(gripper: GripperName) -> Path:
    """The merged URDF with ``gripper`` as a file only this process can reach (a sealed in-memory file, as
    :func:`bt_grasp.robot_description.robot_urdf_path`: nothing written beside bt_grasp's files or trusted from a
    cache)."""
    if gripper == GripperName.BT_GRASP:
        return robot_urdf_path()
    return sealed_urdf_path(f"ur5_{gripper.value}.urdf", robot_urdf_with(gripper))
