"""Household picks that used to fail, one seed each, on the simulator (issue 28, the pick figure), judged by physics.

- The pen-like rod (tests/data/scenes/lying_rod.yaml, seed 2, trees/pick.xml): held 15 cm up, the arm came to rest
  1 mrad short of the lift's goal and Lift failed on the settle timeout (TRACKING_ERROR); the executor now takes an
  arm at rest within 3 mrad as arrived (tests/motion/test_executor_at_rest.py has the unit test).
- The L bracket (scenes/household.yaml, seed 67, trees/pick.xml): seen 38 mm across, held by its 4 mm plate;
  Grasp called the 4.0 mm gap empty (GRASP_EMPTY, five times in a row with recovery). With the planned grasp
  known, only fingers at their closed limit hold nothing (tests/behaviours/test_thin_grasp.py).
- The T tool (scenes/household.yaml, seed 2, trees/pick.xml): 100 mm across its footprint's narrowest side; no
  grasp was found (NOTHING_TO_GRASP) with recovery, and the footprint's grasp closed on nothing without. It is
  grasped across its stem or its bar from its cloud (tests/perception/test_household_grasps.py).
- The bowl (scenes/household.yaml, seed 18, both trees): 128 mm across, held by its rim 6 cm from its centre; it
  turns 25-30 degrees in the pads as it leaves the table and its centre rose 12.3 cm of 15 (tree SUCCESS, judge
  not). Lift is given the perceived object (``target``) and raises the tool by the height plus how far the
  object may hang below where it is held (tests/behaviours/test_hang.py, test_lift_object.py): its centre rises
  the full height.
- The pen beside a standing mug (scenes/household.yaml, seed 20, trees/pick_with_recovery.xml): the palm across
  the pen's middle met the mug in both footprint grasps (PLAN_FAILED); PlanGrasp then tries the grasps sampled
  from the pen's cloud, one 30 mm along the pen is clear (tests/behaviours/test_plan_approach_leaves.py).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.episode.episode import Episode
from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.episode.result import EpisodeResult

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
HOUSEHOLD = ROOT / "scenes" / "household.yaml"


def _run(tmp_path: Path, tree: str, scene: Path, seed: int, color: str = "") -> EpisodeResult:
    blackboard: dict[str, str | float] = {"color": color, "lift_height": 0.15}
    request = EpisodeRequest(tree=ROOT / "trees" / tree, scene=scene, seed=seed, blackboard=blackboard,
                             log=tmp_path / f"{scene.stem}_{seed}.mcap")
    return Episode(request).run()


def _assert_picked(result: EpisodeResult, name: str) -> None:
    assert result.success and result.tree_status == "SUCCESS", result.to_json()
    judged = result.judged
    assert judged.success and judged.object_name == name and judged.in_gripper, judged
    assert judged.lifted_objects == (name,), judged.lifted_objects


def test_the_rod_lifted_without_a_settle_timeout(tmp_path: Path) -> None:
    result = _run(tmp_path, "pick.xml", ROOT / "tests" / "data" / "scenes" / "lying_rod.yaml", 2, "red")
    _assert_picked(result, "rod")


@pytest.mark.parametrize(("seed", "name"), [(67, "l_bracket"), (2, "t_tool")])
def test_a_household_object_that_failed_is_picked(tmp_path: Path, seed: int, name: str) -> None:
    _assert_picked(_run(tmp_path, "pick.xml", HOUSEHOLD, seed), name)


@pytest.mark.parametrize("tree", ["pick.xml", "pick_with_recovery.xml"])
def test_a_bowl_held_by_its_rim_rises_the_full_height(tmp_path: Path, tree: str) -> None:
    result = _run(tmp_path, tree, HOUSEHOLD, 18)
    _assert_picked(result, "bowl")
    assert result.judged.object_lift_m >= 0.15, result.judged  # the full height, not only within the slack


def test_a_pen_whose_middle_lies_by_a_mug_is_grasped_along_it(tmp_path: Path) -> None:
    _assert_picked(_run(tmp_path, "pick_with_recovery.xml", HOUSEHOLD, 20), "pen")
