"""Reading and checking a scene's mesh and URDF objects when the scene loads (bad input: one sentence, exit 2).

A ``shape: mesh`` object names an OBJ, STL, PLY, GLB, GLTF or DAE file; a ``shape: urdf`` object names a URDF
describing one rigid body (:mod:`bt_grasp.scene.urdf_object`: mesh or primitive parts, each at its
``<origin>``). Paths are relative to the file that names them. Each file is read once, under a size limit, and
checked: a regular file, a mesh at all, not empty, at most :data:`~bt_grasp.scene.mesh_files.MAX_MESH_FACES`
triangles, a collision mesh not degenerate (its vertices must span a volume), of a plausible size once scaled (at
least 1 mm, at most the table's largest side), and a URDF's mass positive. The files a mesh names (materials,
textures, buffers) are read once too, inside the mesh's folder, and checked before any decoder sees them
(:mod:`bt_grasp.scene.mesh_files`); trimesh parses only those bytes, and the renderer is given a copy of them
(``VisualPart.sources``), never a path a file named. A drawn file whose materials name a texture image that is
missing, or that lies outside its folder (never opened), is drawn in its material's colour. The result is a
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
from bt_grasp.files.bounded_io import MAX_MESH_BYTES, read_user_file
from bt_grasp.files.config import KeyPath
from bt_grasp.scene.mesh_files import (
    MAX_MESH_FACES,
    MAX_MESH_PIECES,
    MAX_MESH_VERTICES,
    MeshFiles,
    checked_resolver,
    read_mesh_files,
    renderer_copy,
)
from bt_grasp.scene.mesh_geometry import MeshGeometry, Vec3, VisualPart
from bt_grasp.scene.notices import notice
from bt_grasp.scene.objects import DEFAULT_MESH_RGB, MESH_SUFFIXES
from bt_grasp.scene.urdf_object import MeshRef, Primitive, UrdfObject, UrdfPart

log = logging.getLogger(__name__)

if TYPE_CHECKING:
    from bt_grasp.scene.objects import SceneObject

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
        scale_line = lines.get((*where, i, "scale"), line)
        # numbers past float64's range (scale: 1e308) are refused below in one sentence, not warned about 34 times
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            if obj.shape == "mesh":
                assert obj.mesh is not None
                geometry = read_mesh_object(folder / obj.mesh, obj.scale_xyz, source, line, obj.name, scale_line)
            else:
                assert obj.urdf is not None
                geometry = read_urdf_object(folder / obj.urdf, obj.scale_xyz, source, line, obj.name, packages,
                                            scale_line, from_visual=obj.collision == "from_visual")
        _check_size(geometry, table_size_m, source, scale_line, obj.name)
        obj.with_geometry(geometry)


def _check_scaled(vertices: np.ndarray, source: str | Path, line: int | None, name: str) -> None:
    """Vertices once scaled must still be finite numbers (``scale: 1e308`` made them infinite)."""
    if not np.all(np.isfinite(vertices)):
        raise ConfigError(source, f"object '{name}': once scaled, its vertices are not finite numbers: check 'scale' "
                          "(the file's units times scale must be metres)", where=line)


def _check_size(geometry: MeshGeometry, table: float, source: str | Path, line: int | None, name: str) -> None:
    lo, hi = np.asarray(geometry.bounds_m[0]), np.asarray(geometry.bounds_m[1])
    largest = float(np.max(hi - lo))
    if largest > table:
        raise ConfigError(source, f"object '{name}' is {largest:.3g} m across once scaled, larger than the table "
                          f"({table:.3g} m): check 'scale' (the file's units times scale must be metres)", where=line)
    if largest < MIN_EXTENT_M:
        raise ConfigError(source, f"object '{name}' is {largest * 1000:.3g} mm across once scaled, smaller than a "
                          "millimetre: check 'scale' (the file's units times scale must be metres)", where=line)


def read_mesh_object(path: Path, scale: Vec3, source: str | Path, line: int | None, name: str,
                     scale_line: int | None = None) -> MeshGeometry:
    """A ``shape: mesh`` object's file, read and checked; errors name the scene file and the object's line."""
    loaded = _load_mesh_file(path, source, line, name, solid=True)
    _textured, fallback = _how_drawn(loaded, path, name)
    vertices = np.asarray(loaded.mesh.vertices, dtype=float) * np.asarray(scale)
    _check_scaled(vertices, source, scale_line or line, name)
    faces = np.asarray(loaded.mesh.faces, dtype=np.int64)
    v, f = _arrays_if_untextured(loaded, fallback, scale)
    visual = VisualPart(T_object_part=np.eye(4), path=path.resolve(), scale=scale, rgba=fallback,
                        vertices_m=v, faces=f, sources=() if v is not None else renderer_copy(loaded.files))
    return _geometry(vertices, faces, hashlib.sha256(loaded.data).hexdigest(), path, scale, (visual,), None,
                     source, line, name, rgb=loaded.rgb, mass_kg=None, piece_faces=loaded.piece_faces)


def read_urdf_object(path: Path, scale: Vec3, source: str | Path, line: int | None, name: str,
                     packages: Mapping[str, Path] | None = None, scale_line: int | None = None,
                     from_visual: bool = False) -> MeshGeometry:
    """A ``shape: urdf`` object (:mod:`bt_grasp.scene.urdf_object`: one rigid body, mesh or primitive parts);
    errors in the URDF name the URDF's line, a missing mesh the line that names it. ``from_visual`` (the scene's
    ``collision: from_visual``): the object collides as what is drawn, its ``<collision>`` parts not read; the
    drawn mesh is made convex pieces as any collision mesh is (a convex body its hull, else CoACD, cached under a
    hash of the drawn geometry)."""
    from bt_grasp.scene.urdf_object import read_urdf  # deferred: the URDF reader loads only for shape: urdf objects

    urdf = read_urdf(_read(path, source, line, name), path, packages)
    _check_scale_keeps_shapes(urdf.visuals + urdf.collisions, scale, source, line, name)
    files: dict[Path, _LoadedMesh] = {}

    def load(ref: MeshRef, part_line: int | None, solid: bool) -> _LoadedMesh:
        if ref.path not in files:
            files[ref.path] = _load_mesh_file(ref.path, path, part_line, name, solid=solid, urdf=True)
        return files[ref.path]

    if from_visual:
        return _urdf_from_visual(urdf, path, scale, source, line, name, scale_line,
                                 lambda ref, ln: load(ref, ln, False))
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
    _check_scaled(vertices * np.asarray(scale), source, scale_line or line, name)
    return _geometry(vertices * np.asarray(scale), faces, hasher.hexdigest(), collision_path, scale, visuals, drawn,
                     path, where, name, rgb=rgb, mass_kg=urdf.mass_kg, piece_faces=tuple(piece_faces))


def _urdf_from_visual(urdf: UrdfObject, path: Path, scale: Vec3, source: str | Path, line: int | None, name: str,
                      scale_line: int | None, load: Callable[[MeshRef, int | None], _LoadedMesh]) -> MeshGeometry:
    """A URDF object whose collision geometry is its drawn mesh (scaled already: the scale is 1 from here on).
    Its hash is of the drawn triangles, so an edited drawing is decomposed again and the file's own collision
    shapes are never taken for these."""
    visuals, drawn, rgb = _visual_parts(urdf.visuals, scale, name, load)
    vertices, faces = drawn
    _check_scaled(vertices, source, scale_line or line, name)
    hasher = hashlib.sha256(b"bt_grasp urdf collision from_visual 1")
    hasher.update(np.round(vertices, 9).tobytes())
    hasher.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    drawn_path = next((p.geometry.path for p in urdf.visuals if isinstance(p.geometry, MeshRef)), path)
    where = urdf.visuals[0].line if urdf.visuals else line
    return _geometry(vertices, faces, hasher.hexdigest(), drawn_path, (1.0, 1.0, 1.0), visuals, None, path, where,
                     name, rgb=rgb, mass_kg=urdf.mass_kg)


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
                                  faces=af, sources=() if av is not None else renderer_copy(loaded.files)))
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
    """A mesh file read and checked: its bytes, the mesh, its pieces, its material colour, the files it names."""

    data: bytes
    mesh: Any
    piece_faces: tuple[int, ...]  # the file's separate pieces (OBJ objects, scene nodes): their face counts
    rgb: Vec3 | None
    files: MeshFiles


def _how_drawn(loaded: _LoadedMesh, path: Path, name: str) -> tuple[bool, tuple[float, float, float, float] | None]:
    """Whether a drawn file shows its own texture, and the colour to draw it in instead when a texture image it
    names is missing or lies outside its folder, or when the renderer cannot be given a checked copy of its files
    (said once). Asked only of drawn files: a collision file's materials never matter."""
    found = loaded.files
    colour = (*(loaded.rgb or DEFAULT_MESH_RGB), 1.0)
    outside = [ref for ref in found.outside if ref.kind == "texture"]
    for ref in found.outside:  # never opened, never looked at: the sentence is the same whatever is there
        notice(log, f"object '{name}': {path.name} names {ref.kind} file {ref.raw[:120]!r} outside its folder "
                    f"({path.parent}): not read" + (", drawn in its material colour" if ref.kind == "texture" else ""))
    missing = [(ref, n) for ref, n in found.missing if ref.kind == "texture"]
    if missing:
        missing_path = path.parent / missing[0][1]
        notice(log, f"object '{name}': {path.name} names texture image {missing_path.name}, which is missing "
                    f"({missing_path.parent}): drawn in its material colour")
    if found.unstageable:
        notice(log, f"object '{name}': {path.name}: {found.unstageable}, so it is drawn in its material colour")
    if outside or missing or found.unstageable:
        return False, colour
    return bool(found.textures), None


def _load_mesh_file(path: Path, source: str | Path, line: int | None, name: str, *, solid: bool,
                    urdf: bool = False) -> _LoadedMesh:
    data = _read(path, source, line, name)

    def error(problem: str) -> ConfigError:
        return ConfigError(source, f"object '{name}': mesh file '{path}' {problem}", where=line)

    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ConfigError(source, f"object '{name}': '{path.name}' is not one of {', '.join(MESH_SUFFIXES)}",
                          where=line)
    files = read_mesh_files(path, data, error)
    mesh, piece_faces, rgb = _parse_mesh(data, path, source, line, name, solid=solid, files=files)
    return _LoadedMesh(data, mesh, piece_faces, rgb, files)


def _read(path: Path, source: str | Path, line: int | None, name: str) -> bytes:
    try:
        return read_user_file(path, MAX_MESH_BYTES, error=ConfigError)
    except ConfigError as exc:
        raise ConfigError(source, f"object '{name}': cannot read '{path}': {exc.problem}", where=line) from None


def _parse_mesh(data: bytes, path: Path, source: str | Path, line: int | None, name: str, *,
                solid: bool = True, files: MeshFiles) -> tuple[Any, tuple[int, ...], Vec3 | None]:
    """The file's triangles as one mesh (its pieces, OBJ objects or scene nodes, joined in order), each piece's
    face count, and the file's own colour. trimesh reads only the checked bytes of ``files``."""
    import trimesh

    suffix = path.suffix.lower()
    if not data.strip():
        raise ConfigError(source, f"object '{name}': mesh file '{path}' is empty", where=line)
    try:
        resolver = checked_resolver(files)
        options: dict[str, Any] = {"split_objects": True, "group_material": False} if suffix == ".obj" else {}
        loaded = trimesh.load(io.BytesIO(data), file_type=suffix[1:], resolver=resolver, process=False, **options)
        instanced = _instanced(loaded) if isinstance(loaded, trimesh.Scene) else (0, 0)
        if instanced[0] <= MAX_MESH_PIECES and instanced[1] <= MAX_MESH_FACES:
            geometries = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
            pieces = [g for g in geometries if isinstance(g, trimesh.Trimesh) and len(g.faces) and len(g.vertices)]
    except Exception as exc:  # any parser failure of a third-party format reader is bad input here
        raise ConfigError(source, f"object '{name}': mesh file '{path}' cannot be read as a mesh "
                          f"({type(exc).__name__})", where=line) from None
    if instanced[0] > MAX_MESH_PIECES or instanced[1] > MAX_MESH_FACES:  # a scene's nodes instance its meshes
        raise ConfigError(source, f"object '{name}': mesh file '{path}' places {instanced[0]:,} pieces of "
                          f"{instanced[1]:,} triangles in all, more than the {MAX_MESH_PIECES:,} pieces and "
                          f"{MAX_MESH_FACES:,} triangles a mesh may have", where=line)
    if not pieces:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' holds no triangles (an empty mesh)",
                          where=line)
    face_count, vertex_count = sum(len(p.faces) for p in pieces), sum(len(p.vertices) for p in pieces)
    if face_count > MAX_MESH_FACES or vertex_count > MAX_MESH_VERTICES:
        raise ConfigError(source, f"object '{name}': mesh file '{path}' has {face_count:,} triangles and "
                          f"{vertex_count:,} vertices, more than the {MAX_MESH_FACES:,} and "
                          f"{MAX_MESH_VERTICES:,} a mesh may have (simplify it first)", where=line)
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


def _instanced(scene: Any) -> tuple[int, int]:
    """The pieces a trimesh scene places and their triangles, each instance counted (before it is copied out)."""
    pieces = faces = 0
    for node in scene.graph.nodes_geometry:
        pieces += 1
        geometry = scene.geometry.get(scene.graph[node][1])
        faces += len(getattr(geometry, "faces", ()))
        if pieces > MAX_MESH_PIECES:
            break
    return pieces, faces


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
