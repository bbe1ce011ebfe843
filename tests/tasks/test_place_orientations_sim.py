"""The held-out task of issue 28 in the simulator: two 4 cm cubes set down 6 cm apart on one marker
(tests/data/task_scenes/two_boxes_marker.yaml + .xml). Place tries the cube's quarter turns and keeps the first
whose open fingers clear the cube already there: 8 seeds out of 8 succeed, the second cube judged by physics
(the scene's goal) and the first checked with the simulator's truth (tests may read it): still within 1 cm of
where it was set down, upright. With ``turns="false"`` (the one orientation Place tried before) the second
place fails with PLACE_BLOCKED (measured on seeds 0-3: all four; the fingers, closing along the line of the two
cubes, would open into the first one); the test keeps seed ``SINGLE_YAW_FAILS``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.episode.episode import Episode
from bt_grasp.episode.request import EpisodeRequest

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "task_scenes"
#: a seed on which the single orientation is blocked (measured: seeds 0-3 all are)
SINGLE_YAW_FAILS = 1
FIRST_CUBE_XY = (0.36, 0.21)


def _tree(tmp_path: Path, turns: bool) -> Path:
    """The task's tree with ``turns`` set, written to tmp_path (its include made absolute)."""
    text = (DATA / "two_boxes_marker.xml").read_text(encoding="utf-8")
    text = text.replace("../../../trees/lib/pick.xml", str(ROOT / "trees" / "lib" / "pick.xml"))
    if not turns:
        assert text.count('turns="true"/>') == 2
        text = text.replace('turns="true"/>', 'turns="false"/>')
    out = tmp_path / f"two_boxes_marker_{'turns' if turns else 'one'}.xml"
    out.write_text(text, encoding="utf-8")
    return out


def _episode(tmp_path: Path, seed: int, turns: bool) -> Episode:
    return Episode(EpisodeRequest(tree=_tree(tmp_path, turns), scene=DATA / "two_boxes_marker.yaml", seed=seed))


@pytest.mark.parametrize("seed", range(8))
def test_two_cubes_six_cm_apart_on_one_marker(tmp_path: Path, seed: int) -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle

    episode = _episode(tmp_path, seed, turns=True)
    result = episode.run()
    assert result.tree_status == "SUCCESS" and result.success, result.to_json()
    T_red = GroundTruthOracle(episode.world).T_world_object("red_box")
    off = float(np.hypot(*(T_red[:2, 3] - np.asarray(FIRST_CUBE_XY))))
    assert off <= 0.01, f"the first cube ended {off * 100:.1f} cm from where it was set down"
    tilt_deg = math.degrees(math.acos(min(1.0, float(T_red[2, 2]))))
    assert tilt_deg < 10.0, f"the first cube is tilted {tilt_deg:.0f} deg"


def test_the_single_orientation_is_blocked_on_a_seed(tmp_path: Path) -> None:
    result = _episode(tmp_path, SINGLE_YAW_FAILS, turns=False).run()
    assert not result.success and result.tree_status == "FAILURE", result.to_json()
    assert result.reason == "PLACE_BLOCKED", result.to_json()
