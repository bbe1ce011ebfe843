"""What a mesh or URDF object's files hold, once read and checked: the typed result the scene loader attaches
to the object and the simulator builds from (no file is read twice, no decision is made again)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Literal

import numpy as np

Vec3 = tuple[float, float, float]
RGBA = tuple[float, float, float, float]


@dataclass(frozen=True, eq=False)
class VisualPart:
    """One drawn piece of an object: a mesh file (``path``, drawn with ``scale``) or a primitive (``primitive``:
    ``box`` with ``dims_m`` its x, y, z sizes, ``cylinder`` radius and length along z, ``sphere`` radius), at
    ``T_object_part`` (4x4, metres, scale applied), in ``rgba`` when given (a URDF's material colour for a file
    without a texture, or the material colour of a file whose texture image is missing), else the file's own
    materials. A file whose texture image is missing is drawn from ``vertices_m``/``faces`` (the part's frame,
    scaled) instead of the file: the renderer refuses a file that names a missing image. ``sources``: what the
    renderer is given for a drawn file, the file and the files it names as checked when read, names inside them
    rewritten to these (``bt_grasp.scene.mesh_files.renderer_copy``; the file first): never ``path`` itself."""

    T_object_part: np.ndarray
    path: Path | None = None
    scale: Vec3 = (1.0, 1.0, 1.0)
    primitive: Literal["box", "cylinder", "sphere"] | None = None
    dims_m: tuple[float, ...] = ()
    rgba: RGBA | None = None
    vertices_m: np.ndarray | None = None
    faces: np.ndarray | None = None
    sources: tuple[tuple[str, bytes], ...] = ()

    @cached_property
    def _sources_digest(self) -> str:
        digest = hashlib.sha256()
        for name, data in self.sources:
            digest.update(f"{name}\0{len(data)}\0".encode())
            digest.update(data)
        return digest.hexdigest()

    def _identity(self) -> tuple[object, ...]:
        return (self.path, self.scale, self.primitive, self.dims_m, self.rgba,
                tuple(np.round(np.asarray(self.T_object_part, dtype=float), 12).ravel()), self._sources_digest)


@dataclass(frozen=True, eq=False)
class MeshGeometry:
    """One object's geometry in its own frame, metres (the file's units times the scene's ``scale``).

    ``vertices_m``/``faces`` are the collision mesh (a URDF's ``<collision>`` parts, else its visual ones, placed
    in the object's frame and joined); ``visuals`` are what is drawn, and ``visual_vertices_m``/``visual_faces``
    the same joined into one mesh (for viewers); ``sha256`` is a hash of the collision geometry's content, the key
    of its cached collision shapes (:mod:`bt_grasp.scene.mesh_cache`).
    """

    collision_path: Path  # the (first) collision mesh file; the URDF itself when every collision is a primitive
    scale: Vec3  # the scale the collision vertices were read with (the scene's times the URDF's, for one file)
    vertices_m: np.ndarray  # (N, 3) float64
    faces: np.ndarray  # (M, 3) int64
    sha256: str
    bounds_m: tuple[Vec3, Vec3]  # (min xyz, max xyz) of the collision mesh
    volume_m3: float  # the mesh's volume when it is closed, else its convex hull's
    visuals: tuple[VisualPart, ...] = ()
    visual_vertices_m: np.ndarray | None = None  # None: the collision mesh is what is drawn
    visual_faces: np.ndarray | None = None
    rgb: Vec3 | None = None  # the object's own colour (a URDF material's, else its visual file's), when it has one
    mass_kg: float | None = None  # a URDF's <inertial><mass>, when it gives one
    #: the collision mesh's separate pieces in ``faces`` order, as their files give them (a URDF's <collision>
    #: elements, an OBJ's objects: a V-HACD file's hulls), by face count; () when it is one piece
    piece_faces: tuple[int, ...] = ()

    @property
    def visual_path(self) -> Path:
        """The (first) drawn mesh file; the collision file when every visual is a primitive."""
        return next((v.path for v in self.visuals if v.path is not None), self.collision_path)

    def visual_mesh_m(self) -> tuple[np.ndarray, np.ndarray]:
        """The drawn geometry joined into one mesh, object frame, metres (vertices, faces)."""
        if self.visual_vertices_m is None or self.visual_faces is None:
            return self.vertices_m, self.faces
        return self.visual_vertices_m, self.visual_faces

    def _identity(self) -> tuple[object, ...]:
        return (self.collision_path, self.scale, self.sha256, self.rgb, self.mass_kg, self.piece_faces,
                tuple(v._identity() for v in self.visuals))

    def __eq__(self, other: object) -> bool:
        """Equal when read from the same files with the same content and scale (a scene loaded twice, or
        pickled to a worker, equals itself)."""
        return isinstance(other, MeshGeometry) and self._identity() == other._identity()

    def __hash__(self) -> int:
        return hash(self._identity())
