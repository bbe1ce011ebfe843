"""What a mesh or URDF object's files hold, once read and checked: the typed result the scene loader attaches
to the object and the simulator builds from (no file is read twice, no decision is made again)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class MeshGeometry:
    """One object's geometry in its own frame, metres (the file's units times the scene's ``scale``).

    ``vertices_m``/``faces`` are the collision mesh (a URDF's ``<collision>`` mesh, else the visual one);
    ``visual_path`` is the file drawn (with ``scale``); ``sha256`` is the collision file's content hash, the key
    of its cached collision shapes (:mod:`bt_grasp.scene.mesh_cache`).
    """

    visual_path: Path
    collision_path: Path
    scale: Vec3
    vertices_m: np.ndarray  # (N, 3) float64
    faces: np.ndarray  # (M, 3) int64
    sha256: str
    bounds_m: tuple[Vec3, Vec3]  # (min xyz, max xyz) of the collision mesh
    volume_m3: float  # the mesh's volume when it is closed, else its convex hull's
    rgb: Vec3 | None = None  # the file's own material colour, when it has one
    mass_kg: float | None = None  # a URDF's <inertial><mass>, when it gives one

    def _identity(self) -> tuple[object, ...]:
        return (self.visual_path, self.collision_path, self.scale, self.sha256, self.rgb, self.mass_kg)

    def __eq__(self, other: object) -> bool:
        """Equal when read from the same files with the same content and scale (a scene loaded twice, or
        pickled to a worker, equals itself)."""
        return isinstance(other, MeshGeometry) and self._identity() == other._identity()

    def __hash__(self) -> int:
        return hash(self._identity())
