"""The held object is modelled while carrying: it moves with the tool and collides with scene shapes."""

from __future__ import annotations

import numpy as np

from bt_grasp.geometry import make_T
from bt_grasp.motion.collision import collision_checker
from bt_grasp.motion.kinematics import default_kinematics
from bt_grasp.motion.planning_scene import Box, PlanningScene
from bt_grasp.scene.format import Scene


def test_a_carried_box_collides_with_a_shape_the_bare_gripper_misses() -> None:
    kin = default_kinematics()
    q = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])
    T_tcp = kin.fk(q)
    # an obstacle 6-10 cm straight below the tool centre point: the fingers end above it
    below = T_tcp.copy()
    below[:3, :3] = np.eye(3)
    below[2, 3] -= 0.08
    obstacle = Box.at("neighbour", (0.04, 0.04, 0.04), below)
    scene = PlanningScene.from_scene(Scene(), (obstacle,))
    assert collision_checker(scene).is_valid(q)
    # a 10 cm tall box held with its centre 4 cm below the tcp reaches down to 9 cm below it
    held = Box.at("held", (0.05, 0.05, 0.10), make_T(translation=[0.0, 0.0, 0.04]))
    carrying = scene.with_attached(held, "tcp")
    checker = collision_checker(carrying)
    assert not checker.is_valid(q)
    assert ("neighbour", "attached:held") in checker.colliding_pairs(q)
    # moved up by 10 cm, the carried box clears it again
    q_up = kin.ik(make_T(T_tcp[:3, :3], T_tcp[:3, 3] + [0, 0, 0.10]), q).q
    assert checker.is_valid(q_up)


def test_a_checker_answers_the_same_whatever_it_was_asked_before() -> None:
    """GJK warm starts once hid a deep penetration after a sweep of queries (regression)."""
    kin = default_kinematics()
    R = np.diag([1.0, -1.0, -1.0])
    obstacle = Box.at("object_0", (0.055, 0.055, 0.05), make_T(translation=[0.4, -0.2, 0.0225]))
    held = Box.at("held", (0.054, 0.054, 0.054), make_T(translation=[0.0, 0.0, 0.01]))
    scene = PlanningScene.from_scene(Scene(), (obstacle,)).with_attached(held, "tcp")
    q = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])
    checker = collision_checker(scene)
    answers = []
    for x, y in [(0.35, 0.2), (0.38, 0.0), (0.4, -0.2)]:
        for z in np.linspace(0.15, 0.038, 12):
            q = kin.ik(make_T(R, [x, y, z]), q).q
            answers.append(checker.is_valid(q))
    fresh = type(checker)(checker.robot, scene)
    assert not answers[-1] and not fresh.is_valid(q)
