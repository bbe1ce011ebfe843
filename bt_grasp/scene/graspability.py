"""Whether the cell's gripper can pick an object at all, from the object's geometry and mass alone: an object
wider than the gripper opens on every side, or heavier than two pads' friction holds, can be in a scene (an
obstacle, a distractor) but never be picked. The scene loader says so once, in one sentence, when the scene
loads (``bt-grasp scene validate`` prints it); a run on it ends with the tree's own failure reason
(``NOTHING_TO_GRASP``: no grasp fits, ``SLIPPED``: it is too heavy)."""

from __future__ import annotations

import numpy as np

from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene.mesh_geometry import MeshGeometry

#: m/s^2, to turn a friction force into the mass it holds
GRAVITY_M_S2 = 9.81


def narrowest_width_m(geometry: MeshGeometry) -> float:
    """The object's smallest width over all directions (the narrowest gap two parallel pads could span): the
    least extent of its convex hull along one of the hull's face normals."""
    import trimesh

    hull = trimesh.Trimesh(vertices=geometry.vertices_m, faces=geometry.faces, process=True).convex_hull
    normals = np.unique(np.round(np.asarray(hull.face_normals, dtype=float), 9), axis=0)
    spans = np.ptp(np.asarray(hull.vertices, dtype=float) @ normals.T, axis=0)
    return float(spans.min())


def holdable_mass_kg(gripper_force_n: float, finger_friction: float, object_friction: float) -> float:
    """The heaviest object two pads pressing ``gripper_force_n`` hold by friction (the simulator's friction between
    two materials is their mean)."""
    mu = (finger_friction + object_friction) / 2.0
    return 2.0 * mu * gripper_force_n / GRAVITY_M_S2


def cannot_pick(name: str, geometry: MeshGeometry, mass_kg: float | None, object_friction: float,
                gripper_force_n: float, finger_friction: float, max_opening_m: float = MAX_OPENING_M) -> str | None:
    """A sentence saying why the gripper can never pick this object, or None when it might."""
    width = narrowest_width_m(geometry)
    if width > max_opening_m:
        return (f"object '{name}' is {width * 1000:.0f} mm across at its narrowest, wider than the gripper opens "
                f"({max_opening_m * 1000:.0f} mm): it cannot be picked (a run on it ends NOTHING_TO_GRASP)")
    limit = holdable_mass_kg(gripper_force_n, finger_friction, object_friction)
    if mass_kg is not None and mass_kg > limit:
        return (f"object '{name}' weighs {mass_kg:.3g} kg, more than the gripper's {gripper_force_n:.0f} N "
                f"holds by friction ({limit:.2g} kg): it cannot be lifted (a run on it ends SLIPPED or GRASP_EMPTY)")
    return None
