"""Reading and checking a scene's mesh and URDF objects when the scene loads (bad input: one sentence, exit 2).

A ``shape: mesh`` object names an OBJ, STL, PLY, GLB or GLTF file; a ``shape: urdf`` object names a URDF with
one link and no joints whose ``<visual>``/``<collision>`` geometry are meshes. Paths are relative to the file
that names them. Each file is read once, under a size limit, and checked: present and readable, a mesh at all,
not empty, not degenerate (its vertices must span a volume), of a plausible size once scaled (at least 1 mm, at
most the table's largest side), and a URDF's mass positive. The result is a
:class:`~bt_grasp.scene.mesh_geometry.MeshGeometry` attached to the object. Nothing is written anywhere.
"""

from __future__ import annotations

import hashlib
import io
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_grasp.bounded_io import read_user_file
from bt_grasp.config import KeyPath
from bt_grasp.errors import ConfigError
from bt_grasp.scene.mesh_geometry import MeshGeometry, Vec3
from bt_grasp.scene.objects import MESH_SUFFIXES

if TYPE_CHECKING:
    from bt_grasp.scene.objects import SceneObject

#: the largest mesh or URDF file read, bytes
MAX_MESH_BYTES = 64 << 20
#: the smallest object: its largest extent, m
MIN_EXTENT_M = 0.001
#: vertices closer than this to a line or a plane (m) span no volume
DEGENERATE_TOL_M = 1e-6


def attach_geometry(objects: Sequence[SceneObject], table_size_m: float, source: str | Path,
                    lines: dict[KeyPath, int]) -> None:
    """Read every mesh/URDF object's files (relative to ``source``, the scene file) and attach the result;
    ``table_size_m`` (the table's largest side) bounds an object's size."""
    folder = Path(source).parent
    for i, obj in enumerate(objects):
        if not obj.is_mesh:
            continue
        key = ("objects", i, obj.shape)
        line = lines.get(key, lines.get(("objects", i)))
        if obj.shape == "mesh":
            assert obj.mesh is not None
            geometry = read_mesh_object(folder / obj.mesh, obj.scale_xyz, source, line, obj.name)
        else:
            assert obj.urdf is not None
            geometry = read_urdf_object(folder / obj.urdf, obj.scale_xyz, source, line, obj.name)
        _check_size(geometry, table_size_m, source, lines.get(("objects", i, "scale"), line), obj.name)
        obj.with_geometry(geometry)


def _check_size(geometry: MeshGeometry, table: float, source: str | Path, line: int | None, name: str) -> None:
    lo, hi = np.asarray(geometry.bounds_m[0]), np.asarray(geometry.bounds_m[1])
    largest = float(np.max(hi - lo))
    if largest > table:
        raise ConfigError(source, f"object '{name}' is {largest:.3g} m across once scaled, larger than the table "
                          f"({table:.3g} m): check 'scale' (the file's units times scale must be metres)", where=line)
    if largest < MIN_EXTENT_M:
        raise ConfigError(source, f"object '{name}' is {largest * 1000:.3g} mm across once scaled, smaller than a "
                          "millimetre: check 'scale' (the file's units times scale must be metres)", where=line)


def read_mesh_object(path: Path, scale: Vec3, source: str | Path, line: int | None, name: str) -> MeshGeometry:
    """A ``shape: mesh`` object's file, read and checked; errors name the scene file and the object's line."""
    data = _read(path, source, line, name)
    mesh = _parse_mesh(data, path, source, line, name)
    return _geometry(mesh, data, path, path, scale, source, line, name, mass_kg=None)


def read_urdf_object(path: Path, scale: Vec3, source: str | Path, line: int | None, name: str) -> MeshGeometry:
    """A ``shape: urdf`` object: one link, no joints, mesh geometry; errors in the URDF name the URDF's line."""
    from defusedxml import ElementTree
    from defusedxml.common import DefusedXmlException

    data = _read(path, source, line, name)
    text = data.decode("utf-8", errors="replace")
    try:
        root = ElementTree.fromstring(data)
    except (ElementTree.ParseError, DefusedXmlException) as exc:
        raise ConfigError(path, f"is not a readable URDF ({type(exc).__name__}: {exc})") from None
    if root.tag != "robot":
        raise ConfigError(path, f"is not a URDF: its root element is <{root.tag}>, not <robot>", where=1)
    joints = root.findall("joint")
    if joints:
        raise ConfigError(path, f"has {len(joints)} joint(s) ('{joints[0].get('name', '?')}'); a URDF object must be "
                          "a single rigid link with no joints", where=_line_of(text, "<joint"))
    links = root.findall("link")
    if len(links) != 1:
        raise ConfigError(path, f"has {len(links)} links; a URDF object must be exactly one link", where=1)
    link = links[0]
    mass_kg = _urdf_mass(link, path, text)
    visual = _urdf_mesh(link, "visual", path, text)
    collision = _urdf_mesh(link, "collision", path, text) or visual
    if visual is None or collision is None:
        raise ConfigError(path, "link has no <mesh> geometry in <visual> or <collision>; a URDF object needs one",
                          where=_line_of(text, "<link"))
    (visual_path, _), (collision_path, file_scale) = visual, collision
    total = (scale[0] * file_scale[0], scale[1] * file_scale[1], scale[2] * file_scale[2])
    mesh_line = _line_of(text, "<collision") if collision is not visual else _line_of(text, "<visual")
    for p in {visual_path, collision_path}:
        if not p.is_file():
            raise ConfigError(path, f"names mesh file '{p.name}', which does not exist next to it", where=mesh_line)
    data = _read(collision_path, path, mesh_line, name)
    mesh = _parse_mesh(data, collision_path, path, mesh_line, name)
    return _geometry(mesh, data, visual_path, collision_path, total, path, mesh_line, name, mass_kg)


def _read(path: Path, source: str | Path, line: int | None, name: str) -> bytes:
    try:
        return read_user_file(path, MAX_MESH_BYTES, error=ConfigError)
    except ConfigError as exc:
        raise ConfigError(source, f"object '{name}': cannot read '{path}': {exc.problem}", where=line) from None


def _parse_mesh(data: bytes, path: Path, source: str | Path, line: int | None, name: str) -> Any:
    import trimesh

    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ConfigError(source, f"object '{name}': '{path.name}' is not one of {', '.join(MESH_SUFFIXES)}",
                          where=line)
    if not data.strip():
        raise ConfigError(source, f"object '{name}': mesh file '{path}' is empty", where=line)
    try:
        resolver = trimesh.resolvers.FilePathResolver(str(path.parent))
        loaded = trimesh.load(io.BytesIO(data), file_type=suffix[1:], resolver=resolver, process=False)
        mesh = loaded.to_geometry() if isinstance(loaded, trimesh.Scene) else loaded
    except Exception as exc:  # any parser failure of a third-party format reader is bad input here
        raise ConfigError(source, f"object '{name}': mesh file '{path}' cannot be read as a mesh "
                          f"({type(exc).__name__})", where=line) from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' holds no triangles (an empty mesh)",
                          where=line)
    vertices = np.asarray(mesh.vertices, dtype=float)
    if not np.all(np.isfinite(vertices)):
        raise ConfigError(source, f"object '{name}': mesh file '{path}' has vertices that are not finite numbers",
                          where=line)
    spread = np.linalg.svd(vertices - vertices.mean(axis=0), compute_uv=False)
    if len(vertices) < 4 or spread[-1] / np.sqrt(len(vertices)) < DEGENERATE_TOL_M:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' is degenerate: its vertices lie on a line "
                          "or a plane and enclose no volume", where=line)
    return mesh


def _geometry(mesh: Any, data: bytes, visual_path: Path, collision_path: Path, scale: Vec3,
              source: str | Path, line: int | None, name: str, mass_kg: float | None) -> MeshGeometry:
    vertices = np.asarray(mesh.vertices, dtype=float) * np.asarray(scale)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    scaled = type(mesh)(vertices=vertices, faces=faces, process=False)
    volume = float(scaled.volume) if scaled.is_watertight and scaled.volume > 0 else float(scaled.convex_hull.volume)
    if not volume > 0:
        raise ConfigError(source, f"object '{name}': mesh file '{collision_path}' encloses no volume", where=line)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return MeshGeometry(
        visual_path=visual_path.resolve(), collision_path=collision_path.resolve(), scale=scale,
        vertices_m=vertices, faces=faces, sha256=hashlib.sha256(data).hexdigest(),
        bounds_m=((float(lo[0]), float(lo[1]), float(lo[2])), (float(hi[0]), float(hi[1]), float(hi[2]))),
        volume_m3=volume, rgb=_material_rgb(mesh), mass_kg=mass_kg,
    )


def _material_rgb(mesh: Any) -> Vec3 | None:
    """The file's own colour (a material's main colour or uniform vertex/face colours), if it has one."""
    visual = getattr(mesh, "visual", None)
    try:
        if getattr(visual, "kind", None) == "texture":
            rgba = visual.material.main_color  # type: ignore[union-attr]
        elif getattr(visual, "defined", False):
            rgba = visual.main_color  # type: ignore[union-attr]
        else:
            return None
    except AttributeError:
        return None
    r, g, b = (float(c) / 255.0 for c in np.asarray(rgba)[:3])
    return (r, g, b)


def _line_of(text: str, needle: str) -> int | None:
    at = text.find(needle)
    return text.count("\n", 0, at) + 1 if at >= 0 else None


def _urdf_mass(link: Any, path: Path, text: str) -> float | None:
    mass = link.find("inertial/mass")
    if mass is None:
        return None
    try:
        value = float(mass.get("value", "nan"))
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise ConfigError(path, f"link mass is {mass.get('value')!r}; a mass must be a positive number of kg",
                          where=_line_of(text, "<mass"))
    return value


def _urdf_mesh(link: Any, kind: str, path: Path, text: str) -> tuple[Path, Vec3] | None:
    element = link.find(f"{kind}/geometry/mesh")
    if element is None:
        return None
    where = _line_of(text, f"<{kind}")
    origin = link.find(f"{kind}/origin")
    if origin is not None and any(float(v) != 0.0 for a in ("xyz", "rpy") for v in origin.get(a, "0 0 0").split()):
        raise ConfigError(path, f"<{kind}> has a non-zero <origin>; put the mesh's own frame where the link's is "
                          "(bt_grasp reads URDF objects whose meshes sit at the link frame)", where=where)
    filename = element.get("filename", "")
    if not filename or "://" in filename.removeprefix("file://"):
        raise ConfigError(path, f"<{kind}> mesh filename '{filename}' must be a path relative to the URDF "
                          "(package:// and other URLs are not resolved)", where=where)
    try:
        parts = [float(v) for v in element.get("scale", "1 1 1").split()]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(np.isfinite(p) and p > 0 for p in parts):
        raise ConfigError(path, f"<{kind}> mesh scale '{element.get('scale')}' must be three positive numbers",
                          where=where)
    return (path.parent / filename.removeprefix("file://")), (parts[0], parts[1], parts[2])
