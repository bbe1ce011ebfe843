"""trees/clear_household.xml end to end on the simulator (issue 28), success judged by physics: household
objects that today's top-down grasps hold (the small box, a wood wedge on the wood table, a grey box) go into
the bin, chosen by geometry (SelectObject shape_class="any"), never by colour. The household_clear.yaml
objects that need 6-DoF grasps (can, banana, pen) are reported per object in docs/perception.md."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.sim

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "tests" / "data" / "scenes" / "household_topdown.yaml"


def test_clear_household_puts_every_object_in_the_bin() -> None:
    from bt_grasp.episode import Episode, EpisodeRequest, WarmWorlds

    request = EpisodeRequest(tree=REPO / "trees/clear_household.xml", scene=SCENE, seed=0, max_ticks=20000,
                             blackboard={"lift_height": 0.15})
    episode = Episode(request, WarmWorlds())
    result = episode.run()
    assert result.success, (result.reason, result.failed_leaf, result.judged)
    assert result.tree_status == "SUCCESS"
    # each object's final centre lies inside the bin's inner footprint (the judge's final poses)
    bin_ = next(f for f in episode.scene.fixtures if f.name == "bin")
    for name in ("small_box", "wedge", "grey_box"):
        xyz = np.array(result.judged.object_poses[name])[:3, 3]
        off = np.abs(xyz[:2] - np.array(bin_.center_xy_m))
        assert np.all(off <= np.array(bin_.inner_size_m) / 2), f"{name} at {xyz} is not over the bin's floor"
