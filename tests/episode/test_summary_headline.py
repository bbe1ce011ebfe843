"""The run summary's headline (issue 46): when the tree succeeded and the goal was not met, the goal's first
unmet condition; a leaf's reason only when the tree failed. A run of three household objects into a bin ended
with the tree SUCCESS and the goal unmet on ``upright``, and its summary began ``reason: GRASP_EMPTY leaf:
still_holding``: a condition the tree asked by design, and a failure it had recovered from."""

from __future__ import annotations

import io

from rich.console import Console

from bt_grasp.cli.run_cmd import print_summary
from bt_grasp.episode import EpisodeResult
from bt_grasp.episode.instruments import PlanningStats
from bt_grasp.episode.result import GOAL_NOT_MET, Judged
from bt_grasp.scene.goals import ClearGoal

CONDITIONS = (("target_exists", True, "mug, duck, box"), ("released", True, "free of the fingers"),
              ("upright", False, "duck tilts 84 deg (at most 10)"), ("resting", True, "still 2.0 s"))


def _result(tree_status: str, reason: str | None, leaf: str | None) -> EpisodeResult:
    goal = ClearGoal(kind="clear", into="bin", upright=True)
    return EpisodeResult(
        success=False, tree_status=tree_status, reason=reason, failed_leaf=leaf, failed_path=leaf, ticks=9000,
        sim_time_s=90.0, wall_time_s=30.0, retries={}, seed=3, goal=goal, log=None,
        judged=Judged(goal=goal, success=False, failed_condition="upright", conditions=CONDITIONS),
        planning=PlanningStats(calls=0, pose_calls=0, wall_s=0.0),
    )


def _printed(result: EpisodeResult) -> list[str]:
    out = io.StringIO()
    print_summary(Console(file=out, width=200, color_system=None), result)
    return [line.strip() for line in out.getvalue().splitlines() if line.strip()]


def test_the_tree_succeeded_and_the_goal_did_not_the_headline_is_the_unmet_condition() -> None:
    lines = _printed(_result("SUCCESS", GOAL_NOT_MET, None))
    assert lines[1] == "goal not met: upright: duck tilts 84 deg (at most 10)"
    assert not any(line.startswith("reason:") for line in lines)


def test_the_tree_failed_the_headline_is_the_failed_leaf_s_reason() -> None:
    lines = _printed(_result("FAILURE", "PLACE_BLOCKED", "clear_one/PlaceIn::40"))
    assert lines[1] == "reason: PLACE_BLOCKED  leaf: clear_one/PlaceIn::40"
    assert lines[2] == "goal not met: upright: duck tilts 84 deg (at most 10)"
