"""Collision shapes for mesh objects: the exact convex hull where the mesh is convex, else a convex
decomposition (CoACD), cached on disk so the second run pays nothing. A mesh made of several separate pieces
(an object set's V-HACD collision file, a URDF with several ``<collision>`` elements) is taken piece by piece:
each convex piece is its own hull, and only a non-convex piece is decomposed.

The cache folder is ``$BT_GRASP_CACHE_DIR/meshes`` when that variable is set, else
``$XDG_CACHE_HOME/bt_grasp/meshes`` (``~/.cache/bt_grasp/meshes``). An entry's file name is a hash of the
collision mesh's content (its file's SHA-256), its scale, CoACD's version and the decomposition's parameters:
never a name from a file, so nothing a scene says can place a file anywhere. Entries are written atomically (a temporary
file in the same folder, then a rename); a damaged entry is computed again. Nothing is written elsewhere.
"""

from __future__ import annotations

import enum
import hashlib
import io
import json
import logging
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_grasp.errors import InputError
from bt_grasp.scene.mesh_geometry import MeshGeometry

log = logging.getLogger(__name__)

#: bump when the cached content's meaning changes (2: separate pieces are taken one by one)
CACHE_FORMAT = 2
CACHE_ENV = "BT_GRASP_CACHE_DIR"
#: a mesh is convex when its volume is within this fraction of its convex hull's
CONVEX_VOLUME_TOL = 0.01
#: a mesh of more separate pieces than this is decomposed as a whole (a scanned mesh's specks, not a V-HACD file)
MAX_PIECES = 64
#: decomposing a mesh of more triangles than this is announced as a warning (it can take minutes)
LONG_DECOMPOSITION_FACES = 2000


@dataclass(frozen=True)
class CoacdParams:
    """CoACD's parameters (seeded: the same mesh gives the same parts)."""

    threshold: float = 0.05  # concavity allowed in each part
    max_convex_hull: int = 16  # at most this many parts
    resolution: int = 2000
    mcts_iterations: int = 100
    seed: int = 0


class ShapeSource(enum.Enum):
    HULL = "convex hull"  # the mesh is convex: its hull is exact
    DECOMPOSITION = "convex decomposition"  # CoACD parts
    PIECES = "convex pieces"  # separate pieces, each convex (its hull) or decomposed


@dataclass(frozen=True, eq=False)
class CollisionShapes:
    """Convex parts in the object's frame, metres (each an (N, 3) vertex array), and where they came from."""

    parts: tuple[np.ndarray, ...]
    source: ShapeSource
    from_cache: bool
    volume_m3: float  # the parts' total volume (for mass from density)


def cache_dir() -> Path:
    root = os.environ.get(CACHE_ENV)
    if root:
        return Path(root) / "meshes"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "bt_grasp" / "meshes"


def cache_key(geometry: MeshGeometry, params: CoacdParams) -> str:
    from importlib.metadata import version

    text = json.dumps({"format": CACHE_FORMAT, "sha256": geometry.sha256, "scale": list(geometry.scale),
                       "coacd": version("coacd"),
                       "params": params.__dict__, "tol": CONVEX_VOLUME_TOL}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def collision_shapes(geometry: MeshGeometry, params: CoacdParams = CoacdParams(),
                     folder: Path | None = None) -> CollisionShapes:
    """The object's convex collision parts: from the cache when there, else computed and cached."""
    folder = folder or cache_dir()
    entry = folder / f"{cache_key(geometry, params)}.npz"
    cached = _read_entry(entry)
    if cached is not None:
        return cached
    shapes = compute_shapes(geometry, params)
    _write_entry(folder, entry, shapes)
    return shapes


def compute_shapes(geometry: MeshGeometry, params: CoacdParams) -> CollisionShapes:
    import trimesh

    pieces = _pieces(geometry)
    if 1 < len(pieces) <= MAX_PIECES:
        parts: list[np.ndarray] = []
        for piece in pieces:
            parts += _piece_shapes(piece, params, geometry)
        volume = float(sum(trimesh.convex.convex_hull(p).volume for p in parts))
        return CollisionShapes(tuple(parts), ShapeSource.PIECES, False, volume)
    mesh = trimesh.Trimesh(vertices=geometry.vertices_m, faces=geometry.faces, process=True)
    hull = mesh.convex_hull
    if _is_convex(mesh, hull):
        return CollisionShapes((np.asarray(hull.vertices, dtype=float),), ShapeSource.HULL, False, float(hull.volume))
    parts = _decompose_logged(mesh, params, geometry)
    volume = float(sum(trimesh.convex.convex_hull(p).volume for p in parts))
    return CollisionShapes(tuple(parts), ShapeSource.DECOMPOSITION, False, volume)


def _pieces(geometry: MeshGeometry) -> list[Any]:
    """The collision mesh's separate pieces: the ones its files give (``piece_faces``), each further split where
    it falls apart into unconnected bodies; slivers that span no volume are left out."""
    import trimesh

    counts = geometry.piece_faces or (len(geometry.faces),)
    pieces = []
    for faces in np.split(np.asarray(geometry.faces), np.cumsum(counts)[:-1]):
        piece = trimesh.Trimesh(vertices=geometry.vertices_m, faces=faces, process=True)
        piece.remove_unreferenced_vertices()
        pieces += piece.split(only_watertight=False) if piece.body_count > 1 else [piece]
    return [p for p in pieces if _spans_a_volume(p)]


def _is_convex(mesh: Any, hull: Any) -> bool:
    return bool(mesh.is_watertight and abs(hull.volume - mesh.volume) <= CONVEX_VOLUME_TOL * hull.volume)


def _spans_a_volume(piece: Any) -> bool:
    """A piece worth a collision shape: four or more points not on one plane (a V-HACD file's flat slivers are not)."""
    v = np.unique(np.asarray(piece.vertices, dtype=float).round(9), axis=0)
    if len(v) < 4:
        return False
    return bool(np.linalg.svd(v - v.mean(axis=0), compute_uv=False)[-1] > 1e-7)


def _piece_shapes(piece: Any, params: CoacdParams, geometry: MeshGeometry) -> list[np.ndarray]:
    hull = piece.convex_hull
    if _is_convex(piece, hull):
        return [np.asarray(hull.vertices, dtype=float)]
    return _decompose_logged(piece, params, geometry)


def _decompose_logged(mesh: Any, params: CoacdParams, geometry: MeshGeometry) -> list[np.ndarray]:
    """CoACD on one mesh, said first: on a large mesh as a warning (the only output a user sees), as the wait can
    be minutes (measured: docs/scenes.md, "Objects no one here made")."""
    sentence = (f"decomposing {geometry.collision_path.name} ({len(mesh.faces)} triangles) into convex parts with "
                "CoACD: once, then read from the cache")
    if len(mesh.faces) > LONG_DECOMPOSITION_FACES:
        log.warning("%s; a large mesh can take minutes", sentence)
    else:
        log.info("%s", sentence)
    return decompose(mesh.vertices, mesh.faces, params)


def decompose(vertices: np.ndarray, faces: np.ndarray, params: CoacdParams) -> list[np.ndarray]:
    """CoACD's convex parts of a mesh (vertex arrays); the one place that runs the decomposition."""
    import coacd

    coacd.set_log_level("error")
    result = coacd.run_coacd(
        coacd.Mesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)),
        threshold=params.threshold, max_convex_hull=params.max_convex_hull, resolution=params.resolution,
        mcts_iterations=params.mcts_iterations, seed=params.seed,
    )
    return [np.asarray(v, dtype=float) for v, _f in result]


def _read_entry(entry: Path) -> CollisionShapes | None:
    try:
        with np.load(entry, allow_pickle=False) as data:
            count = int(data["count"])
            parts = tuple(np.asarray(data[f"part_{i}"], dtype=float) for i in range(count))
            source = ShapeSource(str(data["source"]))
            volume = float(data["volume_m3"])
    except FileNotFoundError:
        return None
    except Exception as exc:  # a damaged or foreign entry: computed again and replaced
        log.info("mesh cache entry %s unreadable (%s); computing it again", entry, type(exc).__name__)
        return None
    if not parts or any(p.ndim != 2 or p.shape[1] != 3 or len(p) < 4 or not np.all(np.isfinite(p)) for p in parts):
        return None
    return CollisionShapes(parts, source, True, volume)


def _write_entry(folder: Path, entry: Path, shapes: CollisionShapes) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        buffer = io.BytesIO()
        arrays: dict[str, np.ndarray] = {f"part_{i}": p for i, p in enumerate(shapes.parts)}
        arrays.update(count=np.asarray(len(shapes.parts)), source=np.asarray(shapes.source.value),
                      volume_m3=np.asarray(shapes.volume_m3))
        np.savez(buffer, allow_pickle=False, **arrays)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(buffer.getvalue())
            os.replace(tmp, entry)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError as exc:
        raise InputError(CACHE_ENV if os.environ.get(CACHE_ENV) else str(folder),
                         f"the mesh cache folder {folder} cannot be written ({exc.strerror or exc})") from None
