"""The pick goal's colour when a run names none: 'red' on the first scenes, any object on a scene of mesh or URDF
objects (an object set's files name no colour the perception knows), the rule `bench pick` already had."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.scene.format import load_scene
from bt_grasp.scene.run_goal import default_color, goal_for_run

MESHES = Path(__file__).resolve().parents[1] / "data" / "meshes"


def test_a_scene_of_mesh_objects_picks_any_object_when_no_colour_is_given() -> None:
    scene = load_scene(MESHES / "scene_vhacd_urdf.yaml")  # no colour named anywhere
    assert default_color(scene.objects) == ""
    goal = goal_for_run(scene, {"lift_height": 0.15})
    assert goal.color is None  # type: ignore[union-attr]
    assert goal_for_run(scene, {"color": "red"}).color == "red"  # type: ignore[union-attr]


def test_a_run_on_an_object_set_without_colours_needs_no_color_flag() -> None:
    """`bt-grasp run TREE --scene S` as a new user types it: no --color. On a scene of mesh/URDF objects that name
    no colour the default was 'red' and the run stopped before it began; now it picks any object, and asking
    for a colour no object has says which exist and how to ask for any."""
    from bt_grasp.episode.episode import load_inputs
    from bt_grasp.episode.request import EpisodeRequest
    from bt_grasp.errors import InputError

    tree, scene = MESHES.parents[2] / "trees" / "pick_with_recovery.xml", MESHES / "scene_vhacd_urdf.yaml"
    goal = load_inputs(EpisodeRequest(tree=tree, scene=scene, blackboard={"lift_height": 0.15})).goal
    assert goal.kind == "pick" and goal.color is None  # type: ignore[union-attr]
    with pytest.raises(InputError) as err:
        load_inputs(EpisodeRequest(tree=tree, scene=scene, blackboard={"color": "red", "lift_height": 0.15}))
    assert "(colours there: none named); give --color '' to pick any object" in err.value.problem
