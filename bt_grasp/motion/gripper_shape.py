"""The open gripper's boxes (palm, finger pads, and the wrist's last link they are bolted to) in the tool frame,
from the robot's own collision model.

A placement that has not chosen an arm configuration yet (``bt_grasp.motion.free_area``) still knows where the
gripper will be relative to the held object (the grasp fixes it): these boxes, placed by the release's tool
pose, are what of the robot comes down to the surface with it (the last wrist link as the box round its mesh).
The rest of the arm, whose pose depends on the configuration, is checked later, with the whole robot, by the
planner.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from bt_grasp.geometry import Mat4, inv
from bt_grasp.motion.collision import robot_collision_model
from bt_grasp.motion.kinematics import other_robot
from bt_grasp.robot_description import ARM_JOINTS, GRIPPER_LINKS, MAX_OPENING_M

#: the links rigidly attached to the tool: where they are follows from the tool pose alone (the gripper and the
#: arm's last link, which the last joint turns with the tool)
TOOL_LINKS = (*GRIPPER_LINKS, ARM_JOINTS[-1].removesuffix("_joint") + "_link")


@dataclass(frozen=True)
class ToolBox:
    """One box of the gripper: its full size and its pose in the tool (tcp) frame."""

    name: str
    size_m: tuple[float, float, float]
    T_tcp_box: Mat4


def gripper_boxes(opening_m: float = MAX_OPENING_M, urdf_path: Path | None = None) -> tuple[ToolBox, ...]:
    """The gripper's collision boxes with the fingers ``opening_m`` apart (the planning model's), tcp frame;
    ``urdf_path``: the robot with another gripper (None: bt_grasp's own)."""
    return _gripper_boxes(opening_m, other_robot(urdf_path))


@lru_cache(maxsize=4)
def _gripper_boxes(opening_m: float, urdf_path: Path | None) -> tuple[ToolBox, ...]:
    model = robot_collision_model(opening_m, urdf_path)
    kin = model.kin
    q = np.zeros(kin.model.nq)
    data = kin.model.createData()
    geom_data = pin.GeometryData(model.geom_model)
    pin.forwardKinematics(kin.model, data, q)
    pin.updateGeometryPlacements(kin.model, data, model.geom_model, geom_data)
    T_tcp_base = inv(kin.fk(q))
    out = []
    for i, obj in enumerate(model.geom_model.geometryObjects):
        if model.geom_link[i] not in TOOL_LINKS:
            continue
        geometry = obj.geometry
        half = getattr(geometry, "halfSide", None)
        T_tcp_geom = T_tcp_base @ geom_data.oMg[i].homogeneous
        if half is not None:  # a box
            size, centre = 2 * np.asarray(half, dtype=float), np.zeros(3)
        else:  # a mesh: the box round it
            geometry.computeLocalAABB()
            lo, hi = np.asarray(geometry.aabb_local.min_), np.asarray(geometry.aabb_local.max_)
            size, centre = hi - lo, (hi + lo) / 2
        T = T_tcp_geom.copy()
        T[:3, 3] = T_tcp_geom[:3, :3] @ centre + T_tcp_geom[:3, 3]
        out.append(ToolBox(model.geom_link[i], (float(size[0]), float(size[1]), float(size[2])), T))
    return tuple(out)
