"""The cell's fixed furniture and the judge's true object poses as ``foxglove.SceneUpdate`` messages.

Fixtures (the table and whatever else the scene file declares) come from the scene file, which the
pipeline may know. True object poses come only from the judge's side (the simulator's oracle) and go to
their own topic, ``/judge/true_objects``, drawn as wireframe-like translucent shapes so nobody mistakes them
for what perception saw. A mesh or URDF object is drawn as the mesh it is: a ``ModelPrimitive`` holding a
binary STL of its visual file in metres (facet normals computed), at most :data:`MAX_MODEL_BYTES`; a larger
visual is drawn as its collision mesh, else that mesh's convex hull, else its bounding box (12 triangles).
"""

from __future__ import annotations

import io
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

import numpy as np
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.CylinderPrimitive_pb2 import CylinderPrimitive
from foxglove_schemas_protobuf.ModelPrimitive_pb2 import ModelPrimitive
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneEntityDeletion_pb2 import SceneEntityDeletion
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from numpy.typing import ArrayLike, NDArray

from bt_grasp.recording import schemas

if TYPE_CHECKING:
    from bt_grasp.scene.format import Scene
    from bt_grasp.scene.mesh_geometry import MeshGeometry

log = logging.getLogger(__name__)

WORLD = "world"
_TABLE_RGBA = (0.72, 0.56, 0.38, 1.0)
#: the largest model embedded for one mesh object: 1 MiB of binary STL (20,970 triangles)
MAX_MODEL_BYTES = 1 << 20
_STL_FACET = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


@dataclass(frozen=True)
class Solid:
    """A shape at a pose: ``shape`` box (size x y z), cylinder (radius, height), sphere (radius), ``model`` (a
    binary STL in ``model``, in the solid's frame and metres; ``size_m`` its extents x y z) or ``label``."""

    name: str
    shape: str
    size_m: tuple[float, ...]
    T_world_solid: ArrayLike
    rgba: tuple[float, float, float, float]
    model: bytes | None = None


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
    elif solid.shape == "model":
        if solid.model is None:
            raise ValueError(f"solid {solid.name!r} has shape 'model' but no model bytes")
        entity.models.append(ModelPrimitive(pose=pose, scale=Vector3(x=1.0, y=1.0, z=1.0), color=colour,
                                            override_color=True, media_type="model/stl", data=solid.model))
    elif solid.shape != "label":
        raise ValueError(f"unknown shape {solid.shape!r}")
    if solid.name:
        top = {"box": solid.size_m[-1] / 2, "cylinder": solid.size_m[-1] / 2,
               "model": max(solid.size_m)}.get(solid.shape, solid.size_m[0])
        entity.texts.append(schemas.text_primitive(np.asarray(solid.T_world_solid, dtype=np.float64), solid.name,
                                                   float(top) + 0.03))
    return entity


def scene_solids(scene: Scene) -> list[Solid]:
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


def fixture_update(scene: Scene, stamp_ns: int) -> SceneUpdate:
    return SceneUpdate(entities=[_entity(stamp_ns, f"fixture{i}", s) for i, s in enumerate(scene_solids(scene))])


def judge_update(stamp_ns: int, solids: Sequence[Solid]) -> SceneUpdate:
    """The true object poses (judge/oracle side only), replacing the ones shown before."""
    deletion = SceneEntityDeletion(timestamp=schemas.timestamp(stamp_ns), type=SceneEntityDeletion.ALL)
    return SceneUpdate(deletions=[deletion], entities=[_entity(stamp_ns, "true", s) for s in solids])


def stl_bytes(vertices: ArrayLike, faces: ArrayLike) -> bytes:
    """A binary STL of a triangle mesh, with its facet normals computed (a viewer lights zero normals black)."""
    v = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    facets = np.zeros(len(v), dtype=_STL_FACET)
    facets["normal"] = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    facets["vertices"] = v
    header = b"bt_grasp object model".ljust(80, b" ")
    return header + len(v).to_bytes(4, "little") + facets.tobytes()


@cache
def object_model(geometry: MeshGeometry) -> bytes:
    """A mesh object's model for a viewer (binary STL, metres, the object's frame), at most MAX_MODEL_BYTES:
    its visual file, else its collision mesh, else that mesh's convex hull, else its bounding box."""
    import trimesh

    vertices, faces = geometry.vertices_m, geometry.faces
    candidates: list[tuple[str, NDArray[np.float64], NDArray[np.int64]]] = []
    drawn = next((v for v in geometry.visuals if v.sources), None)
    if geometry.visual_vertices_m is not None:
        candidates.append(("visual", *geometry.visual_mesh_m()))
    elif geometry.visual_path != geometry.collision_path and drawn is not None:
        try:  # the bytes read and checked when the scene loaded: the file is not opened again
            data = drawn.sources[0][1]
            visual = trimesh.load(io.BytesIO(data), file_type=geometry.visual_path.suffix.lower()[1:],
                                  process=False, force="mesh")
            if not isinstance(visual, trimesh.Trimesh):  # force="mesh" makes one (or raises)
                raise TypeError(f"trimesh read a {type(visual).__name__}, not a mesh")
            candidates.append(("visual", np.asarray(visual.vertices) * np.asarray(geometry.scale), visual.faces))
        except Exception as exc:  # the file was read at load; a viewer's copy falls back to the collision mesh
            log.warning("visual mesh %s not read for the log (%s): drawing its collision mesh", geometry.visual_path,
                        type(exc).__name__)
    candidates.append(("collision", vertices, faces))
    hull = trimesh.Trimesh(vertices=vertices, faces=faces, process=False).convex_hull
    candidates.append(("hull", hull.vertices, hull.faces))
    for kind, v, f in candidates:
        if 84 + 50 * len(f) <= MAX_MODEL_BYTES:
            if kind != candidates[0][0]:
                log.info("%s drawn in the log as its %s (the mesh is over %d bytes)", geometry.visual_path.name, kind,
                         MAX_MODEL_BYTES)
            return stl_bytes(v, f)
    box = trimesh.creation.box(bounds=np.asarray(geometry.bounds_m))
    return stl_bytes(box.vertices, box.faces)
