"""scenes/household.yaml in the simulator: the seed's subset is what the world builds, each object set down in its
drawn rest pose stays in it (standing stays standing, lying stays lying), every object comes to rest on the table,
and no two objects touch or overlap once settled."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.scene.format import load_scene
from bt_grasp.scene.layout import draw_layout
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World

pytestmark = pytest.mark.sim

HOUSEHOLD = Path(__file__).resolve().parents[2] / "scenes" / "household.yaml"


def _tilt_deg(T: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(T[2, 2], -1.0, 1.0))))


@pytest.mark.parametrize("seed", [1, 4])  # 1: the bottle lying, the small box upside down; 4: the bottle standing
def test_a_drawn_household_scene_settles_apart_in_its_rest_poses(seed: int) -> None:
    scene = load_scene(HOUSEHOLD)
    world = World(scene, seed, source=HOUSEHOLD)
    expected = draw_layout(scene, np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[0])).objects
    assert tuple(world.objects) == tuple(o.name for o in expected), "the world holds the seed's subset"
    assert tuple(o.name for o in world.config.objects) == tuple(world.objects), "and its config says so"
    oracle = GroundTruthOracle(world)
    names = set(world.objects)
    for placed in world.placed:
        name = placed.spec.name
        T = oracle.T_world_object(name)
        drawn_tilt, tilt = _tilt_deg(placed.T_world_object), _tilt_deg(T)
        assert abs(tilt - drawn_tilt) < 8.0, f"{name} drawn at {drawn_tilt:.0f} deg tilt rests at {tilt:.0f} deg"
        lowest = float(np.min(placed.spec.geometry.vertices_m @ T[:3, :3].T[:, 2] + T[2, 3]))
        assert abs(lowest) < 0.003, f"{name}'s lowest point is {lowest * 1000:.1f} mm from the table top"
        assert np.linalg.norm(T[:2, 3] - placed.T_world_object[:2, 3]) < 0.01, f"{name} slid or rolled away"
        assert np.linalg.norm(oracle.object_velocity(name)) < 0.01
    touching = sorted(
        tuple(sorted(b.entity.name for b in c.bodies))
        for c in world.scene.get_contacts()
        if {b.entity.name for b in c.bodies} <= names and c.bodies[0].entity.name != c.bodies[1].entity.name
    )
    assert touching == [], f"objects touch after settling: {touching}"
