"""Reading and checking a scene's mesh and URDF objects when the scene loads (bad input: one sentence, exit 2).

A ``shape: mesh`` object names an OBJ, STL, PLY, GLB, GLTF or DAE file; a ``shape: urdf`` object names a URDF
describing one rigid body (:mod:`bt_grasp.scene.urdf_object`: mesh or primitive parts, each at its
``<origin>``). Paths are relative to the file that names them. Each file is read once, under a size limit, and
checked: present and readable, a mesh at all, not empty, a collision mesh not degenerate (its vertices must span
a volume), of a plausible size once scaled (at least 1 mm, at most the table's largest side), and a URDF's mass
positive. A drawn file whose materials name a texture image that is missing is drawn in its material's colour
(:mod:`bt_grasp.scene.mesh_textures`; the renderer would refuse it). The result is a
:class:`~bt_grasp.scene.mesh_geometry.MeshGeometry` attached to the object. Nothing is written anywhere.
"""

from __future__ import annotations

import hashlib
import io
import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_grasp.errors import ConfigError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.config import KeyPath
from bt_grasp.scene.mesh_geometry import MeshGeometry, Vec3, VisualPart
from bt_grasp.scene.notices import notice
from bt_grasp.scene.objects import DEFAULT_MESH_RGB, MESH_SUFFIXES
from bt_grasp.scene.urdf_object import MeshRef, Primitive, UrdfPart

log = logging.getLogger(__name__)

if TYPE_CHECKING:
    from bt_grasp.scene.objects import SceneObject

#: the largest mesh or URDF file read, bytes
MAX_MESH_BYTES = 64 << 20
#: the smallest object: its largest extent, m
MIN_EXTENT_M = 0.001
#: vertices closer than this to a line or a plane (m) span no volume
DEGENERATE_TOL_M = 1e-6


def attach_geometry(objects: Sequence[SceneObject], table_size_m: float, source: str | Path,
                    lines: dict[KeyPath, int], packages: Mapping[str, Path] | None = None,
                    where: KeyPath = ("objects",)) -> None:
    """Read every mesh/URDF object's files (relative to ``source``, the scene file) and attach the result;
    ``table_size_m`` (the table's largest side) bounds an object's size; ``packages`` maps ``package://`` names
    to folders (the scene's ``packages:``); ``where``: the key of the objects' list in the file (errors name its
    lines)."""
    folder = Path(source).parent
    for i, obj in enumerate(objects):
        if not obj.is_mesh:
            continue
        key = (*where, i, obj.shape)
        line = lines.get(key, lines.get((*where, i)))
        if obj.shape == "mesh":
            assert obj.mesh is not None
            geometry = read_mesh_object(folder / obj.mesh, obj.scale_xyz, source, line, obj.name)
        else:
            assert obj.urdf is not None
            geometry = read_urdf_object(folder / obj.urdf, obj.scale_xyz, source, line, obj.name, packages)
        _check_size(geometry, table_size_m, source, lines.get((*where, i, "scale"), line), obj.name)
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
    loaded = _load_mesh_file(path, source, line, name, solid=True)
    _textured, fallback = _how_drawn(loaded, path, name)
    vertices = np.asarray(loaded.mesh.vertices, dtype=float) * np.asarray(scale)
    faces = np.asarray(loaded.mesh.faces, dtype=np.int64)
    v, f = _arrays_if_untextured(loaded, fallback, scale)
    visual = VisualPart(T_object_part=np.eye(4), path=path.resolve(), scale=scale, rgba=fallback,
                        vertices_m=v, faces=f)
    return _geometry(vertices, faces, hashlib.sha256(loaded.data).hexdigest(), path, scale, (visual,), None,
                     source, line, name, rgb=loaded.rgb, mass_kg=None, piece_faces=loaded.piece_faces)


def read_urdf_object(path: Path, scale: Vec3, source: str | Path, line: int | None, name: str,
                     packages: Mapping[str, Path] | None = None) -> MeshGeometry:
    """A ``shape: urdf`` object (:mod:`bt_grasp.scene.urdf_object`: one rigid body, mesh or primitive parts);
    errors in the URDF name the URDF's line, a missing mesh the line that names it."""
    from bt_grasp.scene.urdf_object import read_urdf

    urdf = read_urdf(_read(path, source, line, name), path, packages)
    _check_scale_keeps_shapes(urdf.visuals + urdf.collisions, scale, source, line, name)
    files: dict[Path, _LoadedMesh] = {}

    def load(ref: MeshRef, part_line: int | None, solid: bool) -> _LoadedMesh:
        if ref.path not in files:
            files[ref.path] = _load_mesh_file(ref.path, path, part_line, name, solid=solid, urdf=True)
        return files[ref.path]

    hasher = hashlib.sha256(b"bt_grasp urdf collision 1")
    pieces = []
    piece_faces: list[int] = []
    for part in urdf.collisions:
        v, f, digest = _part_mesh(part, lambda ref, ln: load(ref, ln, True))
        pieces.append((v, f))
        piece_faces += files[part.geometry.path].piece_faces if isinstance(part.geometry, MeshRef) else [len(f)]
        hasher.update(f"{digest} {np.round(part.T_object_part, 9).tolist()}".encode())
    vertices, faces = _join(pieces)
    visuals, drawn, rgb = _visual_parts(urdf.visuals, scale, name, lambda ref, ln: load(ref, ln, False))
    collision_path = next((p.geometry.path for p in urdf.collisions if isinstance(p.geometry, MeshRef)), path)
    where = urdf.collisions[0].line
    return _geometry(vertices * np.asarray(scale), faces, hasher.hexdigest(), collision_path, scale, visuals, drawn,
                     path, where, name, rgb=rgb, mass_kg=urdf.mass_kg, piece_faces=tuple(piece_faces))


def _check_scale_keeps_shapes(parts: tuple[UrdfPart, ...], scale: Vec3, source: str | Path, line: int | None,
                              name: str) -> None:
    """A scene ``scale`` that differs per axis cannot stretch a part turned by its ``<origin>`` (nor a sphere)."""
    if max(scale) - min(scale) <= 1e-12 * max(scale):
        return
    for part in parts:
        R = part.T_object_part[:3, :3]
        turned = not np.allclose(np.abs(R), np.abs(R).round(), atol=1e-9) or not np.allclose(np.abs(R), np.eye(3))
        if turned or (isinstance(part.geometry, Primitive) and part.geometry.kind != "box"):
            raise ConfigError(source, f"object '{name}': a scale that differs per axis cannot stretch its URDF's "
                              f"part at line {part.line} (turned by its <origin>, or round); give one number",
                              where=line)


def _part_mesh(part: UrdfPart, load: Callable[[MeshRef, int | None], _LoadedMesh]
               ) -> tuple[np.ndarray, np.ndarray, str]:
    """A collision part as a triangle mesh in the object's frame (before the scene's scale), and its digest."""
    import trimesh

    g = part.geometry
    if isinstance(g, MeshRef):
        loaded = load(g, part.line)
        v = np.asarray(loaded.mesh.vertices, dtype=float) * np.asarray(g.scale)
        f = np.asarray(loaded.mesh.faces, dtype=np.int64)
        digest = f"mesh {hashlib.sha256(loaded.data).hexdigest()} {list(g.scale)}"
    else:
        if g.kind == "box":
            prim = trimesh.creation.box(extents=g.dims_m)
        elif g.kind == "cylinder":
            prim = trimesh.creation.cylinder(radius=g.dims_m[0], height=g.dims_m[1], sections=32)
        else:
            prim = trimesh.creation.icosphere(subdivisions=3, radius=g.dims_m[0])
        v, f = np.asarray(prim.vertices, dtype=float), np.asarray(prim.faces, dtype=np.int64)
        digest = f"{g.kind} {list(g.dims_m)}"
    T = part.T_object_part
    return v @ T[:3, :3].T + T[:3, 3], f, digest


def _join(pieces: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    offsets = np.cumsum([0] + [len(v) for v, _ in pieces[:-1]])
    vertices = np.concatenate([v for v, _ in pieces], axis=0)
    faces = np.concatenate([f + o for (_, f), o in zip(pieces, offsets, strict=True)], axis=0)
    return vertices, faces


def _visual_parts(parts: tuple[UrdfPart, ...], scale: Vec3, name: str,
                  load: Callable[[MeshRef, int | None], _LoadedMesh]
                  ) -> tuple[tuple[VisualPart, ...], tuple[np.ndarray, np.ndarray], Vec3 | None]:
    """What a URDF draws: each part placed and scaled, its colour (a URDF colour paints a file without a
    texture; a file whose texture is missing is painted in its material's colour), the joined mesh, the
    object's colour."""
    S = np.asarray(scale)
    out: list[VisualPart] = []
    pieces: list[tuple[np.ndarray, np.ndarray]] = []
    rgb: Vec3 | None = None
    for part in parts:
        T = np.array(part.T_object_part, dtype=float)
        T[:3, 3] *= S
        g = part.geometry
        v, f, _ = _part_mesh(part, load)
        pieces.append((v * S, f))
        if isinstance(g, MeshRef):
            loaded = load(g, part.line)
            textured, fallback = _how_drawn(loaded, g.path, name)
            rgba = fallback if fallback is not None else (None if textured else part.rgba)
            if fallback is not None and part.rgba is not None:
                rgba = part.rgba
            total = (g.scale[0] * scale[0], g.scale[1] * scale[1], g.scale[2] * scale[2])
            av, af = _arrays_if_untextured(loaded, rgba if fallback is not None else None, total)
            out.append(VisualPart(T_object_part=T, path=g.path.resolve(), scale=total, rgba=rgba, vertices_m=av,
                                  faces=af))
            colour = rgba[:3] if rgba is not None else loaded.rgb
        else:
            dims = tuple(d * scale[0] for d in g.dims_m) if g.kind != "box" else tuple(
                d * s for d, s in zip(g.dims_m, scale, strict=True))
            out.append(VisualPart(T_object_part=T, primitive=g.kind, dims_m=dims, rgba=part.rgba))
            colour = part.rgba[:3] if part.rgba is not None else None
        if rgb is None and colour is not None:
            rgb = (float(colour[0]), float(colour[1]), float(colour[2]))
    return tuple(out), _join(pieces), rgb


def _arrays_if_untextured(loaded: _LoadedMesh, fallback: tuple[float, float, float, float] | None,
                          scale: Vec3) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A file whose texture image is missing is drawn from its triangles (the renderer refuses the file)."""
    if fallback is None:
        return None, None
    return (np.asarray(loaded.mesh.vertices, dtype=float) * np.asarray(scale),
            np.asarray(loaded.mesh.faces, dtype=np.int64))


@dataclass(frozen=True, eq=False)
class _LoadedMesh:
    """A mesh file read and checked: its bytes, the mesh, its pieces, its material colour."""

    data: bytes
    mesh: Any
    piece_faces: tuple[int, ...]  # the file's separate pieces (OBJ objects, scene nodes): their face counts
    rgb: Vec3 | None


def _how_drawn(loaded: _LoadedMesh, path: Path, name: str) -> tuple[bool, tuple[float, float, float, float] | None]:
    """Whether a drawn file shows its own texture, and the colour to draw it in instead when a texture image it
    names is missing (said once). Asked only of drawn files: a collision file's materials never matter."""
    from bt_grasp.scene.mesh_textures import missing_textures, texture_files

    textures = texture_files(path, loaded.data)
    missing = missing_textures(path, loaded.data)
    if not missing:
        return bool(textures), None
    notice(log, f"object '{name}': {path.name} names texture image {missing[0].name}, which is missing "
                f"({missing[0].parent}): drawn in its material colour")
    return False, (*(loaded.rgb or DEFAULT_MESH_RGB), 1.0)


def _load_mesh_file(path: Path, source: str | Path, line: int | None, name: str, *, solid: bool,
                    urdf: bool = False) -> _LoadedMesh:
    if urdf and not path.is_file():
        raise ConfigError(source, f"names mesh file '{path}', which does not exist", where=line)
    data = _read(path, source, line, name)
    mesh, piece_faces, rgb = _parse_mesh(data, path, source, line, name, solid=solid)
    return _LoadedMesh(data, mesh, piece_faces, rgb)


def _read(path: Path, source: str | Path, line: int | None, name: str) -> bytes:
    try:
        return read_user_file(path, MAX_MESH_BYTES, error=ConfigError)
    except ConfigError as exc:
        raise ConfigError(source, f"object '{name}': cannot read '{path}': {exc.problem}", where=line) from None


def _parse_mesh(data: bytes, path: Path, source: str | Path, line: int | None, name: str, *,
                solid: bool = True) -> tuple[Any, tuple[int, ...], Vec3 | None]:
    """The file's triangles as one mesh (its pieces, OBJ objects or scene nodes, joined in order), each piece's
    face count, and the file's own colour."""
    import trimesh

    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ConfigError(source, f"object '{name}': '{path.name}' is not one of {', '.join(MESH_SUFFIXES)}",
                          where=line)
    if not data.strip():
        raise ConfigError(source, f"object '{name}': mesh file '{path}' is empty", where=line)
    try:
        resolver = trimesh.resolvers.FilePathResolver(str(path.parent))
        options: dict[str, Any] = {"split_objects": True, "group_material": False} if suffix == ".obj" else {}
        loaded = trimesh.load(io.BytesIO(data), file_type=suffix[1:], resolver=resolver, process=False, **options)
        geometries = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
        pieces = [g for g in geometries if isinstance(g, trimesh.Trimesh) and len(g.faces) and len(g.vertices)]
    except Exception as exc:  # any parser failure of a third-party format reader is bad input here
        raise ConfigError(source, f"object '{name}': mesh file '{path}' cannot be read as a mesh "
                          f"({type(exc).__name__})", where=line) from None
    if not pieces:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' holds no triangles (an empty mesh)",
                          where=line)
    vertices, faces = _join([(np.asarray(p.vertices, dtype=float), np.asarray(p.faces, dtype=np.int64))
                             for p in pieces])
    if not np.all(np.isfinite(vertices)):
        raise ConfigError(source, f"object '{name}': mesh file '{path}' has vertices that are not finite numbers",
                          where=line)
    if solid:
        _check_spans_a_volume(vertices, path, source, line, name)
    rgb = next((c for c in (_material_rgb(p) for p in pieces) if c is not None), None)
    mesh = pieces[0] if len(pieces) == 1 else trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    return mesh, tuple(len(p.faces) for p in pieces), rgb


def _check_spans_a_volume(vertices: np.ndarray, path: Path, source: str | Path, line: int | None, name: str) -> None:
    spread = np.linalg.svd(vertices - vertices.mean(axis=0), compute_uv=False)
    if len(vertices) < 4 or spread[-1] / np.sqrt(len(vertices)) < DEGENERATE_TOL_M:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' is degenerate: its vertices lie on a line "
                          "or a plane and enclose no volume", where=line)


def _geometry(vertices: np.ndarray, faces: np.ndarray, sha256: str, collision_path: Path, scale: Vec3,
              visuals: tuple[VisualPart, ...], drawn: tuple[np.ndarray, np.ndarray] | None, source: str | Path,
              line: int | None, name: str, rgb: Vec3 | None, mass_kg: float | None,
              piece_faces: tuple[int, ...] = ()) -> MeshGeometry:
    import trimesh

    _check_spans_a_volume(vertices, collision_path, source, line, name)
    scaled = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    volume = float(scaled.volume) if scaled.is_watertight and scaled.volume > 0 else float(scaled.convex_hull.volume)
    if not volume > 0:
        raise ConfigError(source, f"object '{name}': mesh file '{collision_path}' encloses no volume", where=line)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return MeshGeometry(
        collision_path=collision_path.resolve(), scale=scale, vertices_m=vertices, faces=faces, sha256=sha256,
        bounds_m=((float(lo[0]), float(lo[1]), float(lo[2])), (float(hi[0]), float(hi[1]), float(hi[2]))),
        volume_m3=volume, visuals=visuals, visual_vertices_m=None if drawn is None else drawn[0],
        visual_faces=None if drawn is None else drawn[1], rgb=rgb, mass_kg=mass_kg,
        piece_faces=piece_faces if len(piece_faces) > 1 else (),
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
