"""The household wedge on scenes/household_clear.yaml, seen by the simulated D435 (noise on), is detected with
nearly its full length and its centre on its middle (issue 28's clear-table figure). Before, only its thick
half was measured (44.5-47.2 mm of 90 mm, the centre 21-23 mm towards the thick end on seeds 0-2), and set
down by that centre in a corner of the bin the wedge landed on the wall, tilted 32-35 degrees. The truth is
the oracle's (tests may; the pipeline never does); the calibration is the oracle's too, so the figures are
perception's own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.sim

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes" / "household_clear.yaml"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_wedge_is_seen_nearly_whole_in_the_simulator(seed: int) -> None:
    from bt_grasp.perception.config import PerceptionConfig
    from bt_grasp.perception.pipeline import perceive
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    world = World.from_file(SCENE, seed)
    oracle = GroundTruthOracle(world)
    world.step(world.steps_per_tick * 10)
    result = perceive(world.camera.capture(), oracle.T_base_camera_cv(), PerceptionConfig.for_scene(world.config))
    assert result.ok, result.message
    T = oracle.T_base_object("wedge")  # the mesh's origin is the middle of its 90 x 45 mm bottom
    wedge = min(result.others, key=lambda d: float(np.hypot(*(np.asarray(d.centroid_base_m[:2]) - T[:2, 3]))))
    off = np.asarray(wedge.centroid_base_m[:2]) - T[:2, 3]
    assert float(np.hypot(*off)) <= 0.006, off
    assert wedge.size_m[0] >= 0.078, wedge.size_m  # 82-83 mm: its thin end under 8 mm is not seen
    assert abs(wedge.size_m[1] - 0.045) <= 0.004, wedge.size_m
    along = abs(float(np.dot([np.cos(wedge.yaw_rad), np.sin(wedge.yaw_rad)], T[:2, 0])))
    assert along >= np.cos(np.radians(5.0)), (wedge.yaw_rad, T[:2, 0])
