"""Collision shapes for mesh objects: the exact convex hull where the mesh is convex, else a convex
decomposition (CoACD), cached on disk so the second run pays nothing. A mesh made of several separate pieces
(an object set's V-HACD collision file, a URDF with several ``<collision>`` elements) is taken piece by piece:
each convex piece is its own hull, and only a non-convex piece is decomposed.

The cache folder is ``$BT_GRASP_CACHE_DIR/meshes`` when that variable is set, else
``$XDG_CACHE_HOME/bt_grasp/meshes`` (``~/.cache/bt_grasp/meshes``; an empty or relative ``XDG_CACHE_HOME`` is
ignored, as its specification says). An entry's file name is a hash of the
collision mesh's content (its file's SHA-256), its scale, CoACD's version and the decomposition's parameters:
never a name from a file, so nothing a scene says can place a file anywhere. Entries are written atomically (a temporary
file in the same folder, then a rename). Nothing is written elsewhere.

**Trust.** Whoever can write an entry can write its hash too, so the folder is used only when it is a plain
folder owned by this user that nobody else can write (:mod:`bt_grasp.files.private_folder`; otherwise one
sentence, exit 2), and every entry is read as hostile anyway: by the bounded reader (a regular file of at most
16 MB), its zip members' declared sizes checked before anything is inflated, then its content against the mesh it
is for (finite parts of 4 or more vertices, at most :data:`MAX_CACHED_PARTS`, inside the mesh's bounds, a finite
positive volume no larger than the parts can hold). A wrong entry is computed again and replaced.

**Limits.** The decomposition runs in a child process with a time limit (:data:`DECOMPOSITION_LIMIT_S`) and a
memory limit, on at most :data:`MAX_DECOMPOSITION_FACES` triangles: past either it is one sentence naming the file
(a 5-million-face OBJ sat in CoACD until killed at 5 minutes). Duplicate faces are dropped first: they made a
convex box look non-convex.
"""

from __future__ import annotations

import enum
import hashlib
import io
import json
import logging
import os
import resource
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import MAX_CACHE_ENTRY_BYTES, read_user_file
from bt_grasp.files.private_folder import check_private
from bt_grasp.scene.mesh_files import MAX_MESH_VERTICES
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
#: the most triangles the convex decomposition takes, and how long (``BT_GRASP_DECOMPOSITION_LIMIT_S`` sets another
#: limit: the fuzz suite's 3 s) and how much memory it may use
MAX_DECOMPOSITION_FACES = 200_000
DECOMPOSITION_LIMIT_S = 900.0
DECOMPOSITION_LIMIT_ENV = "BT_GRASP_DECOMPOSITION_LIMIT_S"
DECOMPOSITION_MEMORY_BYTES = 4 << 30
#: the most convex parts a cache entry may hold (64 pieces of at most 16 parts each)
MAX_CACHED_PARTS = MAX_PIECES * 16


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
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(xdg) if os.path.isabs(xdg) else Path.home() / ".cache"  # relative or empty: ignored (XDG's rule)
    return base / "bt_grasp" / "meshes"


def _private_cache(folder: Path) -> Path:
    """``folder`` made if missing (0700) and checked: only a folder no one else controls is trusted."""
    source = CACHE_ENV if os.environ.get(CACHE_ENV) else str(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    except OSError as exc:
        raise InputError(source, f"the mesh cache folder {folder} cannot be written ({exc.strerror or exc})") from None
    check_private(folder, source, "the mesh cache")
    return folder


def cache_key(geometry: MeshGeometry, params: CoacdParams) -> str:
    from importlib.metadata import version  # deferred: start-up time (only when a cache key is made)

    text = json.dumps({"format": CACHE_FORMAT, "sha256": geometry.sha256, "scale": list(geometry.scale),
                       "coacd": version("coacd"),
                       "params": params.__dict__, "tol": CONVEX_VOLUME_TOL}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def collision_shapes(geometry: MeshGeometry, params: CoacdParams = CoacdParams(),
                     folder: Path | None = None) -> CollisionShapes:
    """The object's convex collision parts: from the cache when there, else computed and cached."""
    folder = _private_cache(folder or cache_dir())
    entry = folder / f"{cache_key(geometry, params)}.npz"
    cached = _read_entry(entry, geometry)
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
    mesh.update_faces(mesh.unique_faces())  # a face listed twice made a convex box look non-convex
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
        piece.update_faces(piece.unique_faces())
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
    name = geometry.collision_path.name
    if len(mesh.faces) > MAX_DECOMPOSITION_FACES:
        raise InputError(geometry.collision_path, f"its collision mesh has {len(mesh.faces):,} triangles (not convex), "
                         f"more than the {MAX_DECOMPOSITION_FACES:,} the convex decomposition takes: simplify it, or "
                         "give a convex collision mesh or one of convex pieces")
    sentence = (f"decomposing {name} ({len(mesh.faces)} triangles) into convex parts with "
                "CoACD: once, then read from the cache")
    if len(mesh.faces) > LONG_DECOMPOSITION_FACES:
        log.warning("%s; a large mesh can take minutes", sentence)
    else:
        log.info("%s", sentence)
    try:
        return decompose(mesh.vertices, mesh.faces, params)
    except DecompositionError as exc:
        raise InputError(geometry.collision_path, f"its convex decomposition {exc}") from None


class DecompositionError(Exception):
    """The decomposition's child process did not finish: past its time or memory limit, or it failed."""


def decompose(vertices: np.ndarray, faces: np.ndarray, params: CoacdParams) -> list[np.ndarray]:
    """CoACD's convex parts of a mesh (vertex arrays); the one place that runs the decomposition: in a child
    process, under :data:`DECOMPOSITION_LIMIT_S` and :data:`DECOMPOSITION_MEMORY_BYTES` (CoACD cannot be stopped
    from its caller's thread). Arrays go both ways as ``.npz`` without pickle."""
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, vertices=np.asarray(vertices, dtype=float),
             faces=np.asarray(faces, dtype=np.int64), params=np.asarray(json.dumps(params.__dict__)))
    code = "from bt_grasp.scene.mesh_cache import decompose_here; decompose_here()"
    limit_s = _decomposition_limit_s()
    try:
        proc = subprocess.run([sys.executable, "-c", code], input=buffer.getvalue(), capture_output=True,
                              timeout=limit_s, preexec_fn=_child_limits, check=False,
                              env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        raise DecompositionError(f"took more than {limit_s:g} seconds and was stopped: simplify the mesh, or give a "
                                 "convex collision mesh or one of convex pieces") from None
    if proc.returncode != 0:
        last = (proc.stderr.decode("utf-8", "replace").strip().splitlines() or ["no detail"])[-1][:200]
        raise DecompositionError(f"failed (exit {proc.returncode}, past its "
                                 f"{DECOMPOSITION_MEMORY_BYTES >> 30} GiB memory limit or: {last})")
    with np.load(io.BytesIO(proc.stdout), allow_pickle=False) as data:
        return [np.asarray(data[f"part_{i}"], dtype=float) for i in range(int(data["count"]))]


def _decomposition_limit_s() -> float:
    try:
        value = float(os.environ.get(DECOMPOSITION_LIMIT_ENV, "") or DECOMPOSITION_LIMIT_S)
    except ValueError:
        return DECOMPOSITION_LIMIT_S
    return value if 0 < value <= DECOMPOSITION_LIMIT_S else DECOMPOSITION_LIMIT_S


def _child_limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (DECOMPOSITION_MEMORY_BYTES, DECOMPOSITION_MEMORY_BYTES))


def decompose_here() -> None:
    """The child's side of :func:`decompose`: a mesh on stdin, its parts on stdout."""
    import coacd

    with np.load(io.BytesIO(sys.stdin.buffer.read()), allow_pickle=False) as data:
        vertices, faces = data["vertices"], data["faces"]
        params = CoacdParams(**json.loads(str(data["params"])))
    coacd.set_log_level("error")
    result = coacd.run_coacd(
        coacd.Mesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)),
        threshold=params.threshold, max_convex_hull=params.max_convex_hull, resolution=params.resolution,
        mcts_iterations=params.mcts_iterations, seed=params.seed,
    )
    out = io.BytesIO()
    parts = {f"part_{i}": np.asarray(v, dtype=float) for i, (v, _f) in enumerate(result)}
    np.savez(out, allow_pickle=False, count=np.asarray(len(parts)), **parts)
    sys.stdout.buffer.write(out.getvalue())


def _read_entry(entry: Path, geometry: MeshGeometry) -> CollisionShapes | None:
    """The cached shapes, or None (then computed again and replaced) when the entry is missing or wrong in any way
    (see the module's Trust paragraph)."""
    if not os.path.lexists(entry):
        return None
    try:
        raw = read_user_file(entry, MAX_CACHE_ENTRY_BYTES)
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            members = archive.infolist()
            if len(members) > MAX_CACHED_PARTS + 3 or sum(m.file_size for m in members) > 4 * MAX_CACHE_ENTRY_BYTES:
                raise ValueError("more or larger members than an entry holds")
        with np.load(io.BytesIO(raw), allow_pickle=False) as data:
            count = int(data["count"])
            if not 1 <= count <= MAX_CACHED_PARTS or len(data.files) != count + 3:
                raise ValueError(f"{count} parts")
            parts = tuple(np.asarray(data[f"part_{i}"], dtype=float) for i in range(count))
            source = ShapeSource(str(data["source"]))
            volume = float(data["volume_m3"])
    except Exception as exc:  # a damaged, foreign or hostile entry: computed again and replaced
        log.info("mesh cache entry %s unreadable (%s); computing it again", entry, type(exc).__name__)
        return None
    problem = _entry_problem(parts, volume, geometry)
    if problem:
        log.info("mesh cache entry %s is wrong (%s); computing it again", entry, problem)
        return None
    return CollisionShapes(parts, source, True, volume)


def _entry_problem(parts: tuple[np.ndarray, ...], volume: float, geometry: MeshGeometry) -> str:
    """What is wrong with cached shapes for ``geometry`` ('' when nothing)."""
    if any(p.ndim != 2 or p.shape[1] != 3 or len(p) < 4 or not np.all(np.isfinite(p)) for p in parts):
        return "a part that is not 4 or more finite points"
    if sum(len(p) for p in parts) > MAX_MESH_VERTICES:
        return "more vertices than a mesh may have"
    lo, hi = np.asarray(geometry.bounds_m[0]), np.asarray(geometry.bounds_m[1])
    margin = 0.05 * float(np.max(hi - lo)) + 1e-4
    if any(np.any(p.min(axis=0) < lo - margin) or np.any(p.max(axis=0) > hi + margin) for p in parts):
        return "a part outside the mesh's bounds"
    box = float(np.prod(hi - lo + 2 * margin))
    if not (np.isfinite(volume) and 0.0 < volume <= box * len(parts)):
        return f"a volume of {volume!r} m^3"
    return ""


def _write_entry(folder: Path, entry: Path, shapes: CollisionShapes) -> None:
    try:
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
