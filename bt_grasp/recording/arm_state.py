"""The arm state of one tick as log messages: ``/robot/joint_state`` (JSON) and ``/tf`` (every link's pose).

One function of plain inputs, so the same bytes come out whether the recorder encodes them itself or its
writer process does (``writer_process.py``): the joint angles, velocities and gripper width, the tool pose,
every link's pose from one forward kinematics pass of the robot description, and the static transforms.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bt_grasp.recording import schemas
from bt_grasp.recording.encodings import dumps
from bt_grasp.recording.jsonable import to_jsonable
from bt_grasp.recording.tf_encoding import FrameTransformsEncoder


def ticked(tick: int | None, msg: dict[str, object]) -> dict[str, object]:
    """``msg`` tagged with the last tick written; before the first tick the key is left out (Foxglove's JSON
    schemas have no nullable types)."""
    return msg if tick is None else {"tick": tick, **msg}


def number(value: object) -> float:
    """A number of an arm state (a float, an int, a numpy scalar) as a float."""
    return float(np.asarray(value, dtype=np.float64))


class LinkPoses(Protocol):
    """A robot description's forward kinematics (:class:`bt_grasp.recording.robot_model.RobotModel`)."""

    def link_xyzquat(self, q_arm: ArrayLike, gripper_width_m: float | None) -> list[tuple[str, list[float]]]: ...


class ArmStateEncoder:
    """Encodes arm states; keeps the static transforms' conversions and the frame names' bytes between ticks.

    ``robot_model``: a :class:`bt_grasp.recording.robot_model.RobotModel` (every link on /tf) or None (the
    tool frame only).
    """

    def __init__(self, joint_names: Sequence[str], base_frame: str, tool_frame: str,
                 robot_model: LinkPoses | None) -> None:
        self.joint_names = list(joint_names)
        self.base_frame = base_frame
        self.tool_frame = tool_frame
        self.robot_model = robot_model
        self._tf = FrameTransformsEncoder()
        self._static_cache: dict[tuple[str, str], tuple[NDArray[np.float64], list[float], list[float]]] = {}

    def encode(self, stamp_file_ns: int, tick: int | None, robot: Mapping[str, object],
               statics: Mapping[tuple[str, str], NDArray[np.float64]]) -> tuple[bytes, bytes | None]:
        """(joint-state JSON, FrameTransforms bytes or None) of ``robot`` = ``{"q_rad", "qd_rad_s",
        "gripper_width_m", "T_base_tcp"}`` at the file time ``stamp_file_ns``."""
        q = np.asarray(robot["q_rad"], dtype=np.float64).ravel()
        qd = robot.get("qd_rad_s")
        state = ticked(tick, {
            "name": self.joint_names[: q.size],
            "position": q.tolist(),
            "velocity": [] if qd is None else np.asarray(qd, dtype=np.float64).ravel().tolist(),
        })
        width = robot.get("gripper_width_m")
        if width is not None:
            state["gripper_width_m"] = number(width)
        links = None
        if self.robot_model is not None:  # every link's pose (one FK); the tool pose is among them
            links = self.robot_model.link_xyzquat(q, None if width is None else number(width))
        T = robot.get("T_base_tcp")
        M = None
        if T is not None:
            M = schemas.as_matrix(T)
            state["tcp_xyz_m"] = M[:3, 3].tolist()
            state["tcp_quat_xyzw"] = list(schemas.quat_xyzw(M))
        elif links is not None:
            tool = next((v for name, v in links if name == self.tool_frame), None)
            if tool is not None:
                state["tcp_xyz_m"] = tool[:3]
                state["tcp_quat_xyzw"] = tool[3:]
        try:  # plain floats and lists: straight to JSON; NaN or inf (allow_nan=False) take the careful path
            joint_state = dumps(state)
        except ValueError:
            joint_state = dumps(to_jsonable(state))
        frames = self._static_xyzquat(statics)
        if links is not None:  # every link of the robot description, for the 3D view
            base = self.base_frame
            frames += [(base, name, v[:3], v[3:]) for name, v in links]
        elif M is not None:
            x, y, z, w = schemas.quat_xyzw(M)
            frames.append((self.base_frame, self.tool_frame, M[:3, 3].tolist(), [x, y, z, w]))
        return joint_state, (self._tf.encode_xyzquat(stamp_file_ns, frames) if frames else None)

    def _static_xyzquat(self, statics: Mapping[tuple[str, str], NDArray[np.float64]]
                        ) -> list[tuple[str, str, Sequence[float], Sequence[float]]]:
        """The static transforms as (parent, child, xyz, quaternion), converted once per change."""
        out: list[tuple[str, str, Sequence[float], Sequence[float]]] = []
        for (parent, child), T in statics.items():
            cached = self._static_cache.get((parent, child))
            if cached is None or cached[0] is not T:
                M = schemas.as_matrix(T)
                cached = (T, M[:3, 3].tolist(), list(schemas.quat_xyzw(M)))
                self._static_cache[(parent, child)] = cached
            out.append((parent, child, cached[1], cached[2]))
        return out
