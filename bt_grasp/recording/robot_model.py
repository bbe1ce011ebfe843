"""The robot as a Foxglove viewer draws it: one scene entity per link, and every link's pose per tick.

From the robot description (the merged UR5 + gripper URDF): each link's geometry becomes a
``foxglove.SceneEntity`` in that link's frame (``frame_locked``, so it follows the frame), with the UR5's
collision meshes embedded as STL ``ModelPrimitive``s (about 270 kB for the whole arm; the visual COLLADA
meshes weigh 6.5 MB) and the gripper's boxes as cubes. Forward kinematics (pinocchio, on the same URDF)
gives every link's pose in the base frame for ``/tf`` each tick. No URL, no ``package://``: any viewer of
the file alone draws the arm.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import defusedxml.ElementTree as SafeET
import numpy as np
import pinocchio as pin
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.ModelPrimitive_pb2 import ModelPrimitive
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from numpy.typing import ArrayLike, NDArray

from bt_grasp.recording import schemas
from bt_grasp.robot_description import ARM_JOINTS, FINGER_JOINT, MIMIC_FINGER_JOINT, robot_urdf_text

_ARM_RGBA = (0.62, 0.66, 0.72, 1.0)


@dataclass(frozen=True)
class LinkVisual:
    """One piece of a link's geometry: a mesh file or a box, at ``T_link_geom``."""

    link: str
    T_link_geom: NDArray[np.float64]
    mesh: Path | None
    box_m: tuple[float, float, float] | None
    rgba: tuple[float, float, float, float]


def _origin(el: object) -> NDArray[np.float64]:
    origin = el.find("origin") if el is not None else None  # type: ignore[attr-defined]
    T = np.eye(4)
    if origin is None:
        return T
    x, y, z = (float(v) for v in origin.get("xyz", "0 0 0").split())
    r, p, yw = (float(v) for v in origin.get("rpy", "0 0 0").split())
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(yw), math.sin(yw)
    T[:3, :3] = np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                          [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                          [-sp, cp * sr, cp * cr]])
    T[:3, 3] = (x, y, z)
    return T


def link_visuals(urdf_text: str) -> list[LinkVisual]:
    """Every link's drawable geometry: its visual box, or else its collision mesh (STL)."""
    robot = SafeET.fromstring(urdf_text)
    out: list[LinkVisual] = []
    for link in robot.iter("link"):
        name = link.get("name", "")
        for visual in link.findall("visual"):
            box = visual.find("geometry/box")
            if box is None:
                continue
            size = tuple(float(v) for v in box.get("size", "0 0 0").split())
            colour = visual.find("material/color")
            rgba = tuple(float(v) for v in colour.get("rgba").split()) if colour is not None else _ARM_RGBA
            out.append(LinkVisual(name, _origin(visual), None, size, rgba))  # type: ignore[arg-type]
        for collision in link.findall("collision"):
            mesh = collision.find("geometry/mesh")
            if mesh is not None and mesh.get("filename", "").lower().endswith(".stl"):
                out.append(LinkVisual(name, _origin(collision), Path(mesh.get("filename", "")), None, _ARM_RGBA))
    return out


class RobotModel:
    """Link poses by forward kinematics and the link entities, for one robot description."""

    def __init__(self, urdf_text: str | None = None) -> None:
        text = urdf_text if urdf_text is not None else robot_urdf_text()
        self.model = pin.buildModelFromXML(text)
        self.data = self.model.createData()
        self.visuals = link_visuals(text)
        self._arm_idx = [self.model.joints[self.model.getJointId(j)].idx_q for j in ARM_JOINTS]
        self._finger_idx = [self.model.joints[self.model.getJointId(j)].idx_q
                            for j in (FINGER_JOINT, MIMIC_FINGER_JOINT) if self.model.existJointName(j)]
        #: the link frames (BODY frames), root excluded: what /tf carries each tick
        self.links: list[tuple[str, int]] = [
            (f.name, i) for i, f in enumerate(self.model.frames)
            if f.type == pin.FrameType.BODY and f.name != "base_link"
        ]
        self.root = "base_link"

    def link_poses(self, q_arm: Sequence[float], gripper_width_m: float | None) -> dict[str, NDArray[np.float64]]:
        """T_base_link of every link, for the arm's joint angles and the gripper's opening."""
        q = pin.neutral(self.model)
        q[self._arm_idx] = np.asarray(q_arm, dtype=np.float64)[: len(self._arm_idx)]
        if gripper_width_m is not None:
            q[self._finger_idx] = 0.5 * float(gripper_width_m)
        pin.framesForwardKinematics(self.model, self.data, q)
        return {name: self.data.oMf[i].homogeneous for name, i in self.links}

    def link_xyzquat(self, q_arm: ArrayLike, gripper_width_m: float | None) -> list[tuple[str, list[float]]]:
        """(link, [x, y, z, qx, qy, qz, qw]) of every link in the base frame: what /tf needs, with no matrix."""
        q = pin.neutral(self.model)
        q[self._arm_idx] = np.asarray(q_arm, dtype=np.float64)[: len(self._arm_idx)]
        if gripper_width_m is not None:
            q[self._finger_idx] = 0.5 * float(gripper_width_m)
        pin.framesForwardKinematics(self.model, self.data, q)
        oMf = self.data.oMf
        return [(name, pin.SE3ToXYZQUAT(oMf[i]).tolist()) for name, i in self.links]

    def scene_update(self, stamp_ns: int) -> SceneUpdate:
        """One entity per link, in the link's frame, that stays until replaced (lifetime 0)."""
        by_link: dict[str, SceneEntity] = {}
        ts = schemas.timestamp(stamp_ns)
        for v in self.visuals:
            entity = by_link.get(v.link)
            if entity is None:
                entity = SceneEntity(timestamp=ts, frame_id=v.link, id=f"robot/{v.link}", frame_locked=True)
                by_link[v.link] = entity
            colour = schemas.color(v.rgba)
            if v.mesh is not None:
                entity.models.append(ModelPrimitive(
                    pose=schemas.pose(v.T_link_geom), scale=Vector3(x=1.0, y=1.0, z=1.0), color=colour,
                    override_color=True, media_type="model/stl", data=_mesh_bytes(str(v.mesh)),
                ))
            elif v.box_m is not None:
                sx, sy, sz = v.box_m
                entity.cubes.append(CubePrimitive(pose=schemas.pose(v.T_link_geom),
                                                  size=Vector3(x=sx, y=sy, z=sz), color=colour))
        return SceneUpdate(entities=list(by_link.values()))


_STL_FACET = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


@cache
def _mesh_bytes(path: str) -> bytes:
    """A binary STL with its facet normals computed: the UR5's collision meshes carry zero normals, which a
    viewer lights as black."""
    data = Path(path).read_bytes()
    count = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if count < 0 or len(data) != 84 + 50 * count:
        return data  # not a binary STL: left as it is
    facets = np.frombuffer(data, dtype=_STL_FACET, count=count, offset=84).copy()
    v = facets["vertices"].astype(np.float64)
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    facets["normal"] = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    return data[:84] + facets.tobytes()


@cache
def default_robot_model() -> RobotModel:
    return RobotModel()
