"""The judge's view of the objects: where the simulator has every object now (ground truth), for the log, and
each object's true extent (bottom, top, centre from its geometry) for the judge's placement conditions.

Only the judge's side may read it: the run's log writes it on ``/judge/true_objects`` for debugging
perception offline, and nothing in the pipeline reads a log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.scene.mesh_geometry import MeshGeometry
from bt_grasp.scene.objects import SceneObject
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World


@dataclass(frozen=True)
class TrueObject:
    name: str
    shape: str  # "box" (size x y z), "cylinder" (radius, height), "sphere" (radius), "mesh" or "urdf" (extents)
    size_m: tuple[float, ...]
    T_world_object: NDArray[np.float64]
    rgb: tuple[float, float, float]
    geometry: MeshGeometry | None = None  # a mesh or urdf object's geometry (its frame is its file's)


def true_objects(world: World) -> list[TrueObject]:
    oracle = GroundTruthOracle(world)
    by_name = {o.name: o for o in world.config.objects}
    out = []
    for name in oracle.object_names():
        obj = by_name.get(name)
        if obj is not None:
            out.append(TrueObject(name, obj.shape, tuple(float(v) for v in obj.dims_m),
                                  np.asarray(oracle.T_world_object(name), dtype=np.float64),
                                  (float(obj.rgb[0]), float(obj.rgb[1]), float(obj.rgb[2])),
                                  obj.geometry if obj.is_mesh else None))
    return out


@dataclass(frozen=True)
class Extent:
    """Where an object's true geometry is in the world now (judge only): its own-frame bounds centre, its lowest
    and highest point. For a mesh or URDF object these come from its collision mesh (whose frame is its file's:
    the household meshes have their origin at the bottom, not the centre); for a primitive, from its size. Any
    rest pose: a bottle lying on its side has its lowest point at ``radius`` under its axis, not ``height / 2``."""

    center_m: tuple[float, float, float]  # the centre of the object's own-frame bounding box, world frame
    bottom_z_m: float  # the lowest point of the object, world z
    top_z_m: float  # the highest point

    @property
    def center_xy_m(self) -> tuple[float, float]:
        return (self.center_m[0], self.center_m[1])


def object_extent(obj: SceneObject, T_world_object: NDArray[np.float64]) -> Extent:
    """``obj``'s :class:`Extent` at pose ``T_world_object`` (its frame: a primitive's centre, a mesh's file
    origin). Exact for every shape: the mesh's vertices (their lowest point is the collision hull's), a box's
    corners, a cylinder's rims by its axis' tilt, a sphere's radius."""
    T = np.asarray(T_world_object, dtype=np.float64)
    R, p = T[:3, :3], T[:3, 3]
    if obj.is_mesh:
        geometry = obj.geometry
        z = np.asarray(geometry.vertices_m, dtype=np.float64) @ R[2] + p[2]
        lo, hi = (np.asarray(b, dtype=np.float64) for b in geometry.bounds_m)
        center = R @ ((lo + hi) / 2) + p
        return Extent((float(center[0]), float(center[1]), float(center[2])), float(z.min()), float(z.max()))
    size = obj.size_m
    assert size is not None
    if obj.shape == "box":
        half_z = 0.5 * float(np.abs(R[2]) @ np.asarray(size[:3], dtype=np.float64))
    elif obj.shape == "cylinder":  # axis = the object's z; its rims reach h/2 |cos| + r |sin| of the tilt
        cos_tilt = min(1.0, abs(float(R[2, 2])))
        half_z = size[1] / 2 * cos_tilt + size[0] * math.sqrt(max(0.0, 1.0 - cos_tilt * cos_tilt))
    else:  # sphere
        half_z = size[0]
    return Extent((float(p[0]), float(p[1]), float(p[2])), float(p[2] - half_z), float(p[2] + half_z))
