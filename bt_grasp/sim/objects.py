"""Building the scene's objects and drawing their poses from a seed (non-overlapping).

Primitives are built from their sizes; mesh and URDF objects (``bt_grasp.scene.objects``) are drawn from their
visual file and collide with the convex parts from :func:`bt_grasp.scene.mesh_cache.collision_shapes` (the hull
of a convex mesh, else its cached CoACD decomposition). A mesh object is drawn with its lowest point
:data:`MESH_DROP_M` above its support; the world lets it settle before the run starts (``World.settle``)."""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sapien

from bt_grasp.errors import ConfigError, LayoutError
from bt_grasp.files.safe_path import join_under
from bt_grasp.geometry import Mat4, convex_hull_xy, make_T, rot_z
from bt_grasp.scene.mesh_cache import collision_shapes
from bt_grasp.scene.mesh_geometry import VisualPart
from bt_grasp.scene.objects import DEFAULT_MESH_RGB, SceneObject
from bt_grasp.sim.poses import to_pose

#: a mesh object starts this far above its support, then settles (a mesh's bottom need not be flat)
MESH_DROP_M = 0.002
# a cylinder in PhysX lies along x; rotate it to stand along z
_CYLINDER_UPRIGHT = sapien.Pose(q=[np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0])


@dataclass(frozen=True)
class PlacedObject:
    spec: SceneObject
    T_world_object: Mat4


def _circle_radius_m(obj: SceneObject, R: np.ndarray | None = None) -> float:
    """The radius about the object's origin of its footprint (a mesh turned by ``R``, its rest rotation)."""
    if obj.is_mesh:
        v = obj.geometry.vertices_m if R is None else obj.geometry.vertices_m @ np.asarray(R).T
        return float(np.max(np.hypot(v[:, 0], v[:, 1])))
    assert obj.size_m is not None
    if obj.shape == "box":
        return float(np.hypot(obj.size_m[0], obj.size_m[1]) / 2)
    return float(obj.size_m[0])


def footprint_xy(obj: SceneObject, T_world_object: Mat4) -> np.ndarray:
    """The object's footprint on the table as a convex polygon (N, 2): a box's 4 corners, a round
    object's circle as 16 points on its circumscribed polygon; a mesh's bounding rectangle (a mesh set down on
    a side, ``T_world_object`` not upright: the convex hull of its vertices seen from above)."""
    if obj.is_mesh and abs(T_world_object[2, 2] - 1.0) > 1e-9:
        return convex_hull_xy(obj.geometry.vertices_m @ T_world_object[:3, :3].T[:, :2] + T_world_object[:2, 3])
    if obj.is_mesh:
        (x0, y0, _), (x1, y1, _) = obj.geometry.bounds_m
        local = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    elif obj.shape == "box":
        assert obj.size_m is not None
        hx, hy = obj.size_m[0] / 2, obj.size_m[1] / 2
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    else:
        assert obj.size_m is not None
        r = obj.size_m[0] / np.cos(np.pi / 16)
        angles = np.arange(16) * 2 * np.pi / 16
        local = np.stack([r * np.cos(angles), r * np.sin(angles)], axis=1)
    R, t = T_world_object[:2, :2], T_world_object[:2, 3]
    return np.asarray(local @ R.T + t)


def footprint_gap_m(a: np.ndarray, b: np.ndarray) -> float:
    """A lower bound of the distance between two convex polygons (separating axes); negative: overlap."""
    best = -np.inf
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for edge in edges:
            n = np.array([-edge[1], edge[0]]) / max(float(np.hypot(*edge)), 1e-12)
            pa, pb = a @ n, b @ n
            best = max(best, float(max(pb.min() - pa.max(), pa.min() - pb.max())))
    return best


def draw_poses(
    objects: tuple[SceneObject, ...], rng: np.random.Generator, table_top_z_m: float, source: str = "scene",
    gap_m: float | None = None, rest: Mapping[str, np.ndarray] | None = None,
) -> list[PlacedObject]:
    """Draw each object's pose within its randomisation ranges (up to 200 tries per object), rejecting
    overlaps: with ``gap_m`` None (a scene that does not say) the circumscribed circles stay 1 cm apart, as
    in the first scene format (so old scenes draw the same poses for a seed); with a number, the exact
    footprints stay at least ``gap_m`` apart (0: objects may touch). ``rest`` gives a mesh object's rest
    rotation (:func:`bt_grasp.scene.layout.draw_layout`), applied before the drawn yaw."""
    placed: list[PlacedObject] = []
    for obj in objects:
        R_rest = None if rest is None or obj.name not in rest else np.asarray(rest[obj.name], dtype=np.float64)
        for _attempt in range(200):
            x = obj.pose.xy_m[0] + rng.uniform(*obj.randomize.x_m)
            y = obj.pose.xy_m[1] + rng.uniform(*obj.randomize.y_m)
            yaw = np.deg2rad(obj.pose.yaw_deg + rng.uniform(*obj.randomize.yaw_deg))
            if gap_m is None:
                r = _circle_radius_m(obj, R_rest)
                clear = all(
                    np.hypot(x - p.T_world_object[0, 3], y - p.T_world_object[1, 3])
                    > r + _circle_radius_m(p.spec, p.T_world_object[:3, :3] if p.spec.is_mesh else None) + 0.01
                    for p in placed
                )
            else:
                mine = footprint_xy(obj, _turned(make_T(rot_z(yaw), [x, y, 0.0]), R_rest))
                clear = all(
                    footprint_gap_m(mine, footprint_xy(p.spec, p.T_world_object)) >= gap_m - 1e-9 for p in placed
                )
            if clear:
                break
        else:
            raise LayoutError(source, f"cannot place object '{obj.name}' without overlapping others", "objects")
        z = resting_z_m(obj, table_top_z_m, R_rest)
        placed.append(PlacedObject(obj, _turned(make_T(rot_z(yaw), [x, y, z]), R_rest)))
    return placed


def _turned(T: Mat4, R_rest: np.ndarray | None) -> Mat4:
    """``T`` (yaw and position) with the object first turned by its rest rotation."""
    if R_rest is None:
        return T
    out = np.array(T, dtype=np.float64)
    out[:3, :3] = out[:3, :3] @ R_rest
    return out


def resting_z_m(obj: SceneObject, support_z_m: float, R_rest: np.ndarray | None = None) -> float:
    """The object frame's height when the object stands on a support at ``support_z_m`` (a primitive's frame is
    its centre; a mesh's is its file's origin, dropped from :data:`MESH_DROP_M` above; ``R_rest``: turned so)."""
    if obj.is_mesh and R_rest is not None:
        return support_z_m - float(np.min(obj.geometry.vertices_m @ R_rest[2])) + MESH_DROP_M
    if obj.is_mesh:
        return support_z_m - obj.geometry.bounds_m[0][2] + MESH_DROP_M
    return support_z_m + obj.height_m / 2


def build_object(scene: sapien.Scene, placed: PlacedObject) -> sapien.Entity:
    obj = placed.spec
    if obj.is_mesh:
        return _build_mesh_object(scene, placed)
    assert obj.size_m is not None
    builder = scene.create_actor_builder()
    material = sapien.physx.PhysxMaterial(obj.friction, obj.friction, 0.0)
    render_material = sapien.render.RenderMaterial(base_color=[*obj.rgb, 1.0], roughness=0.7, metallic=0.0)
    if obj.shape == "box":
        half = [s / 2 for s in obj.size_m]
        builder.add_box_collision(half_size=half, material=material)
        builder.add_box_visual(half_size=half, material=render_material)
    elif obj.shape == "cylinder":
        radius, height = obj.size_m
        builder.add_cylinder_collision(_CYLINDER_UPRIGHT, radius=radius, half_length=height / 2, material=material)
        builder.add_cylinder_visual(_CYLINDER_UPRIGHT, radius=radius, half_length=height / 2, material=render_material)
    else:
        builder.add_sphere_collision(radius=obj.size_m[0], material=material)
        builder.add_sphere_visual(radius=obj.size_m[0], material=render_material)
    mass = obj.mass_or_default_kg
    assert mass is not None  # a primitive has no density_kg_m3
    density = mass / _volume_m3(obj)
    for shape in builder.collision_records:
        shape.density = density
    builder.set_initial_pose(to_pose(placed.T_world_object))
    actor = builder.build(name=obj.name)
    return actor


def _build_mesh_object(scene: sapien.Scene, placed: PlacedObject) -> sapien.Entity:
    """A mesh/URDF object: its visual parts drawn (the scene's colour, else each part's own), convex collision
    parts, a density that gives ``mass_kg`` (or the scene's ``density_kg_m3``), friction as given."""
    obj = placed.spec
    geometry = obj.geometry
    shapes = collision_shapes(geometry)
    if not (np.isfinite(shapes.volume_m3) and shapes.volume_m3 > 0):  # a mass spread over no volume
        raise ConfigError(geometry.collision_path, f"object '{obj.name}': its collision shapes enclose no volume")
    mass = obj.mass_or_default_kg
    density = mass / shapes.volume_m3 if mass is not None else float(obj.density_kg_m3 or 1000.0)
    material = sapien.physx.PhysxMaterial(obj.friction, obj.friction, 0.0)
    body = sapien.physx.PhysxRigidDynamicComponent()
    unit = np.ones(3, dtype=np.float32)
    for part in shapes.parts:
        shape = sapien.physx.PhysxCollisionShapeConvexMesh(np.asarray(part, dtype=np.float32), unit, material)
        shape.set_density(density)
        body.attach(shape)
    render = sapien.render.RenderBodyComponent()
    for visual in geometry.visuals:
        render.attach(_visual_shape(obj, visual))
    entity = sapien.Entity()
    entity.name = obj.name
    entity.add_component(body)
    entity.add_component(render)
    entity.set_pose(to_pose(placed.T_world_object))
    scene.add_entity(entity)
    return entity


def _visual_shape(obj: SceneObject, visual: VisualPart) -> sapien.render.RenderShape:
    """One drawn part: in the scene's colour when it gives one, else the part's (a URDF colour, or the colour of a
    file whose texture is missing), else the file's own materials (a primitive: grey)."""
    rgba = (*obj.rgb, 1.0) if obj.color is not None else visual.rgba
    if rgba is None and visual.primitive is not None:
        rgba = (*DEFAULT_MESH_RGB, 1.0)
    material = None if rgba is None else sapien.render.RenderMaterial(base_color=list(rgba), roughness=0.7,
                                                                       metallic=0.0)
    local = to_pose(visual.T_object_part)
    shape: sapien.render.RenderShape
    if visual.primitive == "box":
        shape = sapien.render.RenderShapeBox(np.asarray(visual.dims_m, dtype=np.float32) / 2, material)
    elif visual.primitive == "cylinder":
        shape = sapien.render.RenderShapeCylinder(visual.dims_m[0], visual.dims_m[1] / 2, material)
        local = local * _CYLINDER_UPRIGHT
    elif visual.primitive == "sphere":
        shape = sapien.render.RenderShapeSphere(visual.dims_m[0], material)
    elif visual.vertices_m is not None and visual.faces is not None:
        shape = _array_mesh_shape(visual.vertices_m, visual.faces, material)
    else:
        assert visual.path is not None and visual.sources
        shape = _file_mesh_shape(obj, visual, material)
    shape.set_local_pose(local)
    return shape


def _file_mesh_shape(obj: SceneObject, visual: VisualPart,
                     material: sapien.render.RenderMaterial | None) -> sapien.render.RenderShapeTriangleMesh:
    """A drawn mesh file, from the checked copy of it and the files it names (``visual.sources``), written to a
    private folder (0700, made for this load) for the renderer, loaded, then removed: the renderer never sees a
    path a file named, nor a file that was not checked. Loading is forced before the folder goes (``get_parts``:
    the renderer reads files lazily, at the first picture otherwise). The folder's name is this process's and the
    content's (the renderer keeps every model it loaded by path for the process's life: one name per content reuses
    it, where a new name per load grew a worker by ~0.4 MB a mesh an episode)."""
    assert visual.path is not None
    with _staged(visual.sources) as main:
        try:
            shape = sapien.render.RenderShapeTriangleMesh(str(main), np.asarray(visual.scale, np.float32), material)
            shape.get_parts()
        except RuntimeError as exc:  # a file the renderer cannot draw (read and checked by trimesh at load)
            problem = str(exc).replace(str(main.parent), str(visual.path.parent))
            raise ConfigError(visual.path, f"object '{obj.name}': the renderer cannot draw this file ({problem})"
                              ) from None
    return shape


@contextmanager
def _staged(sources: tuple[tuple[str, bytes], ...]) -> Iterator[Path]:
    """The files written under a new private folder (removed on leaving); yields the first file's path."""
    digest = hashlib.sha256()
    for name, data in sources:
        digest.update(f"{name}\0{len(data)}\0".encode())
        digest.update(data)
    root = Path(tempfile.gettempdir()) / f"bt_grasp_mesh_{os.getuid()}_{os.getpid()}_{digest.hexdigest()[:32]}"
    try:
        root.mkdir(mode=0o700)
    except FileExistsError:  # someone else's (or a link) at this name: a folder of a new name instead
        root = Path(tempfile.mkdtemp(prefix="bt_grasp_mesh_"))
    try:
        for name, data in sources:
            target = join_under(root, name, source=root, what="mesh file name")
            target.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            with target.open("xb") as f:
                f.write(data)
        yield root / sources[0][0]
    finally:
        shutil.rmtree(root, ignore_errors=True)


def _array_mesh_shape(vertices_m: np.ndarray, faces: np.ndarray,
                      material: sapien.render.RenderMaterial | None) -> sapien.render.RenderShapeTriangleMesh:
    """A drawn mesh from its triangles (smooth vertex normals, no texture coordinates)."""
    import trimesh

    mesh = trimesh.Trimesh(vertices=vertices_m, faces=faces, process=False)
    return sapien.render.RenderShapeTriangleMesh(
        np.asarray(vertices_m, dtype=np.float32), np.asarray(faces, dtype=np.uint32),
        np.asarray(mesh.vertex_normals, dtype=np.float32), np.zeros((len(vertices_m), 2), dtype=np.float32),
        material or sapien.render.RenderMaterial(base_color=[*DEFAULT_MESH_RGB, 1.0], roughness=0.7, metallic=0.0))


def _volume_m3(obj: SceneObject) -> float:
    assert obj.size_m is not None
    if obj.shape == "box":
        return float(np.prod(obj.size_m))
    if obj.shape == "cylinder":
        return float(np.pi * obj.size_m[0] ** 2 * obj.size_m[1])
    return float(4.0 / 3.0 * np.pi * obj.size_m[0] ** 3)
