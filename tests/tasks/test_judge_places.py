"""Which goals the judge must watch tick by tick (where objects came to rest after release) and which it judges
from the end state alone: an episode skips the per-tick contact reading for the latter (`bench budget`)."""

from __future__ import annotations

import pytest

from bt_grasp.scene.goals import ClearGoal, CollectGoal, PickGoal, PlaceGoal, SortGoal, SortRule, StackGoal
from bt_grasp.sim.judge import Judge

pytestmark = pytest.mark.sim  # importing the judge imports the simulator


@pytest.mark.parametrize(("goal", "places"), [
    (PickGoal(kind="pick", color="red"), False),
    (ClearGoal(kind="clear"), False),
    (ClearGoal(kind="clear", into="bin"), True),
    (PlaceGoal(kind="place", object="red_box", at="target_marker"), True),
    (StackGoal(kind="stack", object="red_box", on="blue_box"), True),
    (SortGoal(kind="sort", rules=(SortRule(color="red", into="left_tray"),)), True),
    (CollectGoal(kind="collect", into="bin", count=2), True),
])
def test_only_placement_goals_are_watched_tick_by_tick(goal: object, places: bool) -> None:
    assert Judge.places(goal) is places  # type: ignore[arg-type]
