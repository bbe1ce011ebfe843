"""Whether the cell's gripper can pick an object at all, from the object's geometry and mass alone: an object
wider than the gripper opens on every side, or heavier than two pads' friction holds, can be in a scene (an
obstacle, a distractor) but never be picked. The scene loader says so once, in one sentence, when the scene
loads (``bt-grasp scene validate`` prints it); a run on it ends with the tree's own failure reason
(``NOTHING_TO_GRASP``: no grasp fits, ``SLIPPED``: it is too heavy).

Also said at load: an object whose collision mesh stands well above what is drawn over much of its footprint,
seen from above (pybullet's mug: the collision file makes the cup a solid cylinder). The camera sees the hollow,
the fingers meet a solid: grasps planned into it stall (``TRACKING_ERROR``). That is the object set's modelling,
not something the pipeline can see; the sentence names it."""

from __future__ import annotations

from functools import lru_cache

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


#: the collision mesh reaching this far beyond the drawn one's bounding box is an unseen part, m
UNSEEN_REACH_M = 0.005
#: the drawn mesh reaching this far beyond the collision's bounding box is a part the fingers close through, m
#: (pybullet's YCB cracker box draws 7 mm more than it collides and is picked 10 times in 10)
UNFELT_REACH_M = 0.010
#: the drawn and the collision surfaces are compared on a grid of this cell, m
HEIGHT_CELL_M = 0.002
#: the collision surface this far above the drawn one counts as solid where the camera sees open space, m
HIDDEN_SOLID_M = 0.01
#: the share of the footprint where that is so beyond which the loader says so
HIDDEN_SOLID_SHARE = 0.25


def hidden_solid_share(geometry: MeshGeometry, samples: int = 40000) -> float:
    """The share of the object's footprint (as modelled, seen from above) where its collision mesh is over
    :data:`HIDDEN_SOLID_M` above its drawn mesh; 0 when the drawn mesh is the collision mesh."""
    import trimesh

    if geometry.visual_vertices_m is None or geometry.visual_faces is None:
        return 0.0
    vis_v, vis_f = geometry.visual_mesh_m()
    drawn = trimesh.Trimesh(vertices=vis_v, faces=vis_f, process=False)
    collision = trimesh.Trimesh(vertices=geometry.vertices_m, faces=geometry.faces, process=False)
    if drawn.area <= 0 or collision.area <= 0:
        return 0.0
    p_drawn = np.asarray(trimesh.sample.sample_surface(drawn, samples, seed=0)[0])
    p_coll = np.asarray(trimesh.sample.sample_surface(collision, samples, seed=0)[0])
    lo = np.minimum(p_drawn.min(axis=0), p_coll.min(axis=0))
    hi = np.maximum(p_drawn.max(axis=0), p_coll.max(axis=0))
    shape = tuple(int(n) for n in np.ceil((hi[:2] - lo[:2]) / HEIGHT_CELL_M).astype(int) + 1)

    def top(points: np.ndarray) -> np.ndarray:
        height = np.full(shape, lo[2])
        ij = np.floor((points[:, :2] - lo[:2]) / HEIGHT_CELL_M).astype(int)
        np.maximum.at(height, (ij[:, 0], ij[:, 1]), points[:, 2])
        return height

    coll_top, drawn_top = top(p_coll), top(p_drawn)
    footprint = int(np.count_nonzero(np.maximum(coll_top, drawn_top) > lo[2] + 1e-6))
    hidden = int(np.count_nonzero(coll_top - drawn_top > HIDDEN_SOLID_M))
    return hidden / max(footprint, 1)


def collision_hides_open_space(name: str, geometry: MeshGeometry) -> str | None:
    """A sentence when the collision mesh reaches beyond what is drawn (an unseen part, a collision file in other
    units) or the drawn mesh beyond it, or when it is solid where much of the drawn object is open (see the
    module)."""
    if geometry.visual_vertices_m is None:
        return None
    drawn, _faces = geometry.visual_mesh_m()
    lo, hi = np.asarray(geometry.bounds_m[0]), np.asarray(geometry.bounds_m[1])
    reach = np.concatenate([drawn.min(axis=0) - lo, hi - drawn.max(axis=0)])  # > 0: the collision reaches further
    unseen, unfelt = int(np.argmax(reach)), int(np.argmin(reach))
    if reach[unseen] > UNSEEN_REACH_M:
        return (f"object '{name}': its collision geometry reaches {reach[unseen] * 1000:.0f} mm beyond what is "
                f"drawn (along {_direction(unseen)} of its frame): an unseen part the fingers or the palm meet "
                "(TRACKING_ERROR, COLLISION)")
    if -reach[unfelt] > UNFELT_REACH_M:
        return (f"object '{name}': what is drawn reaches {-reach[unfelt] * 1000:.0f} mm beyond its collision "
                f"geometry (along {_direction(unfelt)} of its frame): the camera sees a part the fingers close "
                "through (GRASP_EMPTY)")
    share = hidden_solid_share(geometry)
    if share <= HIDDEN_SOLID_SHARE:
        return None
    return (f"object '{name}': its collision geometry stands over "
            f"{HIDDEN_SOLID_M * 100:.0f} cm above its drawn surface over {share:.0%} of its footprint seen from above: "
            "a hollow or gap the camera sees is solid to the fingers, and grasps planned into it stall "
            "(TRACKING_ERROR)")


def _direction(index: int) -> str:
    """An index of (min x, min y, min z, max x, max y, max z) as a direction: '-x' ... '+z'."""
    return ("-" if index < 3 else "+") + "xyz"[index % 3]


@lru_cache(maxsize=256)
def object_warning(name: str, geometry: MeshGeometry, mass_kg: float | None, object_friction: float,
                   gripper_force_n: float, finger_friction: float) -> str | None:
    """The one sentence loading says about an object, if any: it can never be picked, else its collision is
    unlike its drawing. Computed once per object and cell (a bench loads its scene every episode)."""
    return (cannot_pick(name, geometry, mass_kg, object_friction, gripper_force_n, finger_friction)
            or collision_hides_open_space(name, geometry))
