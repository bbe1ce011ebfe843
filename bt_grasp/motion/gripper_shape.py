"""The open gripper's boxes (palm and finger pads) in the tool frame, from the robot's own collision model.

A placement that has not chosen an arm configuration yet (``bt_grasp.motion.free_area``) still knows where the
gripper will be relative to the held object (the grasp fixes it): these boxes, placed by the release's tool
pose, are what of the gripper comes down to the surface. The arm above them is checked later, with the whole
robot, by the planner.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import pinocchio as pin

from bt_grasp.geometry import Mat4, inv
from bt_grasp.motion.collision import robot_collision_model
from bt_grasp.robot_description import GRIPPER_LINKS, MAX_OPENING_M


@dataclass(frozen=True)
class ToolBox:
    """One box of the gripper: its full size and its pose in the tool (tcp) frame."""

    name: str
    size_m: tuple[float, float, float]
    T_tcp_box: Mat4


@lru_cache(maxsize=4)
def gripper_boxes(opening_m: float = MAX_OPENING_M) -> tuple[ToolBox, ...]:
    """The gripper's collision boxes with the fingers ``opening_m`` apart (the planning model's), tcp frame."""
    model = robot_collision_model(opening_m)
    kin = model.kin
    q = np.zeros(kin.model.nq)
    data = kin.model.createData()
    geom_data = pin.GeometryData(model.geom_model)
    pin.forwardKinematics(kin.model, data, q)
    pin.updateGeometryPlacements(kin.model, data, model.geom_model, geom_data)
    T_tcp_base = inv(kin.fk(q))
    out = []
    for i, obj in enumerate(model.geom_model.geometryObjects):
        half = getattr(obj.geometry, "halfSide", None)
        if model.geom_link[i] not in GRIPPER_LINKS or half is None:
            continue
        size = tuple(float(2 * h) for h in half)
        out.append(ToolBox(model.geom_link[i], size, T_tcp_base @ geom_data.oMg[i].homogeneous))  # type: ignore[arg-type]
    return tuple(out)
