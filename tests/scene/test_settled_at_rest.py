"""A run begins with every object at rest (issue 46, seen in the learned held-out set): a lying can that lands on
the edge of a facet of its convex hull rolled on at 6-10 cm/s after the 2 s settle (PhysX has no rolling
resistance), so the first look saw it where it would not be and it left the table on its own. The world now damps
the objects' motion while they settle (and only then). On the code before, household seed 128's can rolled at
~8 cm/s when the world was handed over and was ~7 cm away one second later."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.scene.format import load_scene
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import SETTLE_SPEED_M_S, World

pytestmark = pytest.mark.sim

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "household.yaml"


@pytest.mark.parametrize("seed", [128, 146])
def test_objects_are_at_rest_when_the_run_begins_and_stay_there(seed: int) -> None:
    world = World(load_scene(SCENE), seed=seed, source=SCENE)
    oracle = GroundTruthOracle(world)
    names = oracle.object_names()
    assert "can" in names
    start = {n: oracle.T_world_object(n)[:3, 3].copy() for n in names}
    for name in names:
        assert np.linalg.norm(oracle.object_velocity(name)) < SETTLE_SPEED_M_S, name
    for _ in range(100):  # one second, nothing touching them, the simulator's own damping
        world.step_tick()
    for name in names:
        moved = float(np.linalg.norm(oracle.T_world_object(name)[:3, 3] - start[name]))
        assert moved < 0.002, f"{name} moved {moved * 1e3:.1f} mm on its own"
