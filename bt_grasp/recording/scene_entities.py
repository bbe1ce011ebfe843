"""The cell's fixed furniture and the judge's true object poses as ``foxglove.SceneUpdate`` messages.

Fixtures (the table and whatever else the scene file declares) come from the scene file, which the
pipeline may know. True object poses come only from the judge's side (the simulator's oracle) and go to
their own topic, ``/judge/true_objects``, drawn as wireframe-like translucent shapes so nobody mistakes them
for what perception saw.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.CylinderPrimitive_pb2 import CylinderPrimitive
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneEntityDeletion_pb2 import SceneEntityDeletion
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from numpy.typing import ArrayLike

from bt_grasp.recording import schemas

WORLD = "world"
_TABLE_RGBA = (0.72, 0.56, 0.38, 1.0)


@dataclass(frozen=True)
class Solid:
    """A shape at a pose: ``shape`` box (size x y z), cylinder (radius, height) or sphere (radius)."""

    name: str
    shape: str
    size_m: tuple[float, ...]
    T_world_solid: ArrayLike
    rgba: tuple[float, float, float, float]


def _entity(stamp_ns: int, prefix: str, solid: Solid) -> SceneEntity:
    entity = SceneEntity(timestamp=schemas.timestamp(stamp_ns), frame_id=WORLD, id=f"{prefix}/{solid.name}")
    pose = schemas.pose(np.asarray(solid.T_world_solid, dtype=np.float64))
    colour = schemas.color(solid.rgba)
    if solid.shape == "box":
        sx, sy, sz = solid.size_m
        entity.cubes.append(CubePrimitive(pose=pose, size=Vector3(x=sx, y=sy, z=sz), color=colour))
    elif solid.shape == "cylinder":
        r, h = solid.size_m
        entity.cylinders.append(CylinderPrimitive(pose=pose, size=Vector3(x=2 * r, y=2 * r, z=h),
                                                  bottom_scale=1.0, top_scale=1.0, color=colour))
    elif solid.shape == "sphere":
        d = 2 * solid.size_m[0]
        entity.spheres.append(SpherePrimitive(pose=pose, size=Vector3(x=d, y=d, z=d), color=colour))
    elif solid.shape != "label":
        raise ValueError(f"unknown shape {solid.shape!r}")
    if solid.name:
        top = {"box": solid.size_m[-1] / 2, "cylinder": solid.size_m[-1] / 2}.get(solid.shape, solid.size_m[0])
        entity.texts.append(schemas.text_primitive(np.asarray(solid.T_world_solid, dtype=np.float64), solid.name,
                                                   float(top) + 0.03))
    return entity


def scene_solids(scene: Any) -> list[Solid]:
    """The table and the scene file's fixtures, in the world frame (z up, origin on the table top)."""
    sx, sy, sz = scene.table.size_m
    cx, cy = scene.table.center_xy_m
    T = np.eye(4)
    T[:3, 3] = (cx, cy, -0.5 * sz)
    solids = [Solid("", "box", (sx, sy, sz), T, _TABLE_RGBA)]
    for fixture in getattr(scene, "fixtures", ()) or ():
        for part in fixture.parts():  # the parts the simulator builds: floor, walls, patches
            solids.append(Solid("", "box", tuple(part.size_m), part.T_world_part, (*part.rgb, 1.0)))
        T_label = np.asarray(fixture.T_world_fixture(), dtype=np.float64)
        solids.append(Solid(fixture.name, "label", (0.0,), T_label, (1.0, 1.0, 1.0, 1.0)))
    return solids


def fixture_update(scene: Any, stamp_ns: int) -> SceneUpdate:
    return SceneUpdate(entities=[_entity(stamp_ns, f"fixture{i}", s) for i, s in enumerate(scene_solids(scene))])


def judge_update(stamp_ns: int, solids: Sequence[Solid]) -> SceneUpdate:
    """The true object poses (judge/oracle side only), replacing the ones shown before."""
    deletion = SceneEntityDeletion(timestamp=schemas.timestamp(stamp_ns), type=SceneEntityDeletion.ALL)
    return SceneUpdate(deletions=[deletion], entities=[_entity(stamp_ns, "true", s) for s in solids])
