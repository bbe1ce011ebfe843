"""What a run's seed draws before the objects' poses: which objects are on the table (the scene's ``choose``)
and how each mesh or URDF object is set down (its ``rest_pose``).

Both are drawn from the scene's object stream (the same generator that then draws x, y and yaw), in file order:
first the subset, then one rest pose per chosen object whose ``rest_pose`` is not ``modelled``. A scene that
uses neither key draws nothing here, so its poses per seed are what they were before these keys existed.

Rest poses are the mesh's quasi-static stable poses (``trimesh.poses.compute_stable_poses`` on the collision
mesh, without perturbation: deterministic), each with the probability that the object lands on it when dropped
in a random orientation. Poses less likely than :data:`MIN_REST_PROBABILITY` are left out (a bottle balanced on
its cap). ``stable`` draws a pose with those probabilities; ``any_stable`` first draws one of the *distinct*
rest poses uniformly (poses whose tilt of the file's z axis from the vertical rounds to the same
:data:`TILT_BIN_DEG`: a tessellated can lying on any of its 64 sides is one pose, "lying"), then a member of it
by probability. The drawn rotation is the object's orientation before its drawn yaw; it then settles by physics.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import NDArray

from bt_grasp.scene.format import Scene
from bt_grasp.scene.mesh_geometry import MeshGeometry
from bt_grasp.scene.objects import SceneObject

#: stable poses less likely than this (a drop in a random orientation) are never drawn
MIN_REST_PROBABILITY = 0.005
#: rest poses whose file z axis tilts from the vertical by the same angle, to this bin, are one distinct pose
TILT_BIN_DEG = 10.0


@dataclass(frozen=True)
class RestPose:
    """A stable way to set the object down: ``R`` turns the file's frame into the rested one (before yaw)."""

    R: NDArray[np.float64]
    probability: float

    @property
    def tilt_deg(self) -> float:
        """The angle between the file's z axis and the vertical once rested (0: as modelled, 180: upside down)."""
        return float(np.degrees(np.arccos(np.clip(self.R[2, 2], -1.0, 1.0))))


@dataclass(frozen=True)
class Layout:
    """The drawn objects (file order) and the rest rotation of each object that is not set down as modelled."""

    objects: tuple[SceneObject, ...]
    rest: dict[str, NDArray[np.float64]]


@cache
def stable_rest_poses(geometry: MeshGeometry) -> tuple[RestPose, ...]:
    """The collision mesh's stable poses at least :data:`MIN_REST_PROBABILITY` likely, most likely first."""
    import trimesh

    mesh = trimesh.Trimesh(vertices=geometry.vertices_m, faces=geometry.faces, process=False)
    transforms, probabilities = trimesh.poses.compute_stable_poses(mesh, sigma=0.0, n_samples=1, seed=0)
    poses = [RestPose(np.asarray(T, dtype=np.float64)[:3, :3], float(p))
             for T, p in zip(transforms, probabilities, strict=True) if p >= MIN_REST_PROBABILITY]
    poses.sort(key=lambda r: (-round(r.probability, 9), round(r.tilt_deg, 6), tuple(np.round(r.R.ravel(), 9))))
    if not poses:  # every pose below the floor (cannot happen for a closed mesh): as modelled
        return (RestPose(np.eye(3), 1.0),)
    return tuple(poses)


def draw_rest(obj: SceneObject, rng: np.random.Generator) -> NDArray[np.float64]:
    """One rest rotation for a mesh object whose ``rest_pose`` is ``stable`` or ``any_stable``."""
    poses = stable_rest_poses(obj.geometry)
    if obj.rest_pose == "any_stable":
        bins = sorted({round(p.tilt_deg / TILT_BIN_DEG) for p in poses})
        chosen_bin = bins[int(rng.integers(len(bins)))]
        poses = tuple(p for p in poses if round(p.tilt_deg / TILT_BIN_DEG) == chosen_bin)
    weights = np.array([p.probability for p in poses])
    return poses[int(rng.choice(len(poses), p=weights / weights.sum()))].R.copy()


def draw_layout(scene: Scene, rng: np.random.Generator) -> Layout:
    """The objects of one run and their rest rotations, drawn from ``rng`` (the scene's object stream)."""
    objects = scene.objects
    if scene.choose is not None:
        among = scene.choose.among if scene.choose.among is not None else tuple(o.name for o in objects)
        low, high = scene.choose.count_range
        count = int(rng.integers(low, high + 1))
        kept = {among[int(i)] for i in rng.choice(len(among), size=count, replace=False)}
        objects = tuple(o for o in objects if o.name not in among or o.name in kept)
    rest = {o.name: draw_rest(o, rng) for o in objects if o.is_mesh and o.rest_pose != "modelled"}
    return Layout(objects, rest)
