"""The judge's view of the objects for the log: where the simulator has every object now (ground truth).

Only the judge's side may read it: the run's log writes it on ``/judge/true_objects`` for debugging
perception offline, and nothing in the pipeline reads a log.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.scene.mesh_geometry import MeshGeometry
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World


@dataclass(frozen=True)
class TrueObject:
    name: str
    shape: str  # "box" (size x y z), "cylinder" (radius, height), "sphere" (radius), "mesh" or "urdf" (extents)
    size_m: tuple[float, ...]
    T_world_object: NDArray[np.float64]
    rgb: tuple[float, float, float]
    geometry: MeshGeometry | None = None  # a mesh or urdf object's geometry (its frame is its file's)


def true_objects(world: World) -> list[TrueObject]:
    oracle = GroundTruthOracle(world)
    by_name = {o.name: o for o in world.config.objects}
    out = []
    for name in oracle.object_names():
        obj = by_name.get(name)
        if obj is not None:
            out.append(TrueObject(name, obj.shape, tuple(float(v) for v in obj.dims_m),
                                  np.asarray(oracle.T_world_object(name), dtype=np.float64),
                                  (float(obj.rgb[0]), float(obj.rgb[1]), float(obj.rgb[2])),
                                  obj.geometry if obj.is_mesh else None))
    return out
