"""One calibration procedure: `bt-grasp calibrate` (calibrate_in_sim) and the Calibrate leaf in a tree
give the same calibration for the same seed, because they run the same job on the same cell, tick by tick."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.episode import Episode, EpisodeRequest
from bt_grasp.episode.calibration import calibrate_in_sim

pytestmark = [pytest.mark.sim, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes" / "tabletop.yaml"
TREE = """<?xml version="1.0"?>
<root BTCPP_format="4" main_tree_to_execute="Cal">
  <BehaviorTree ID="Cal">
    <Calibrate poses="6"/>
  </BehaviorTree>
</root>
"""


def test_the_command_and_the_leaf_calibrate_identically(tmp_path: Path) -> None:
    tree = tmp_path / "calibrate_only.xml"
    tree.write_text(TREE)
    episode = Episode(EpisodeRequest(tree=tree, scene=SCENE, seed=2))
    result = episode.run()
    assert result.tree_status == "SUCCESS", result
    leaf_run = episode.tree.find("Calibrate").run  # type: ignore[attr-defined]
    command = calibrate_in_sim(SCENE, "eye-to-hand", seed=2, poses=6)
    assert command.run.visited == leaf_run.visited and command.run.rejected == leaf_run.rejected
    assert command.run.solution.method == leaf_run.solution.method
    assert np.array_equal(command.run.solution.X, leaf_run.solution.X)
    assert command.ticks == result.ticks
    # and it is a calibration: within a millimetre of the truth even from six views
    mm, _deg = command.true_error_per_method[command.run.solution.method]
    assert mm < 1.0
