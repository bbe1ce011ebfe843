"""Goals from the command line and from a scene: typed values, bad words refused with the flag named."""

from __future__ import annotations

import pytest

from bt_grasp.defaults import DEFAULT_LIFT_HEIGHT_M
from bt_grasp.errors import InputError
from bt_grasp.scene.format import Scene
from bt_grasp.scene.goals import ClearGoal, PickGoal
from bt_grasp.scene.run_goal import goal_for_run, goal_from_options


def test_command_line_goals() -> None:
    assert goal_from_options("pick", "blue", 0.2) == PickGoal(kind="pick", color="blue", height_m=0.2)
    assert goal_from_options("pick", "", 0.1) == PickGoal(kind="pick", color=None, height_m=0.1)
    assert goal_from_options("clear") == ClearGoal(kind="clear")


@pytest.mark.parametrize(
    ("kind", "height", "flag", "fragment"),
    [
        ("lift", 0.15, "--goal", "expected one of pick, clear, got 'lift'"),
        ("stack", 0.15, "--goal", "declare it in the scene file"),
        ("pick", 0.0, "--lift-height", "within (0, 0.6) m"),
        ("pick", float("nan"), "--lift-height", "within (0, 0.6) m"),
    ],
)
def test_bad_command_line_goals_name_the_flag(kind: str, height: float, flag: str, fragment: str) -> None:
    with pytest.raises(InputError) as info:
        goal_from_options(kind, "red", height)
    assert info.value.source == flag and fragment in str(info.value)


def test_a_scene_without_a_goal_picks_the_runs_colour() -> None:
    scene = Scene()
    assert goal_for_run(scene, {}) == PickGoal(kind="pick", color="red", height_m=DEFAULT_LIFT_HEIGHT_M)
    assert goal_for_run(scene, {"color": "blue", "lift_height": 0.2}) == PickGoal(
        kind="pick", color="blue", height_m=0.2
    )
    with pytest.raises(InputError):
        goal_for_run(scene, {"lift_height": "high"})


def test_a_declared_goal_wins() -> None:
    scene = Scene.model_validate({"version": 2, "goal": {"kind": "clear"}})
    assert goal_for_run(scene, {"color": "red"}) == ClearGoal(kind="clear")
