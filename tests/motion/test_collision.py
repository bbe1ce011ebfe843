"""Collision model: the table, obstacles, the allowed object, self-collision and path checks."""

from __future__ import annotations

import numpy as np

from bt_grasp.geometry import make_T
from bt_grasp.motion.collision import collision_checker, robot_collision_model
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.planning_scene import FINGER_LINKS, Box, Cylinder, PlanningScene
from bt_grasp.robot_description import DISABLED_COLLISION_PAIRS
from tests.motion.conftest import HOME_Q, TOP_DOWN_R


def test_home_is_valid_and_clear(table_scene: PlanningScene) -> None:
    checker = collision_checker(table_scene, 0.01)
    assert checker.is_valid(HOME_Q)
    assert checker.colliding_pairs(HOME_Q) == []
    assert checker.min_distance(HOME_Q) > 0.0


def test_arm_through_the_table_collides(table_scene: PlanningScene) -> None:
    q = HOME_Q.copy()
    q[1] = -0.3  # shoulder lifted down: the forearm goes through the table
    checker = collision_checker(table_scene, 0.0)
    assert not checker.is_valid(q)
    assert ("forearm_link", "table") in checker.colliding_pairs(q)


def test_out_of_limits_and_nan_are_invalid(table_scene: PlanningScene) -> None:
    checker = collision_checker(table_scene, 0.0)
    q = HOME_Q.copy()
    q[2] = 3.5  # elbow limit is pi
    assert not checker.is_valid(q)
    assert not checker.is_valid(np.full(6, np.nan))


def test_disabled_pairs_are_not_checked() -> None:
    robot = robot_collision_model()
    checked = {frozenset((robot.geom_link[a], robot.geom_link[b])) for a, b in robot.self_pairs}
    for pair in DISABLED_COLLISION_PAIRS:
        assert frozenset(pair) not in checked
    assert frozenset(("upper_arm_link", "wrist_1_link")) in checked
    # ee_link is fixed to wrist_3_link and inherits its disabled pairs
    assert frozenset(("wrist_2_link", "ee_link")) not in checked


def test_margin_makes_a_near_miss_invalid(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q = kin.ik(make_T(TOP_DOWN_R, [0.45, 0.0, 0.15]), HOME_Q).q
    fingertip_z = kin.fk(q)[2, 3] - 0.02
    box = Box("block", (0.1, 0.1, 0.1), (0.45, 0.0, fingertip_z - 0.05 - 0.005))  # 5 mm below the tips
    scene = table_scene.with_obstacles(box)
    assert collision_checker(scene, 0.0).is_valid(q)
    assert not collision_checker(scene, 0.01).is_valid(q)


def test_allowed_object_may_touch_the_fingers_only(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q = kin.ik(make_T(TOP_DOWN_R, [0.45, 0.0, 0.025]), HOME_Q).q
    cube = Box("cube", (0.05, 0.05, 0.05), (0.45, 0.0, 0.025))  # the fingers straddle it: pads touch
    wide = Box("cube", (0.05, 0.2, 0.05), (0.45, 0.0, 0.025))
    as_obstacle = collision_checker(table_scene.with_obstacles(wide), 0.0)
    assert not as_obstacle.is_valid(q)
    allowed = table_scene.with_allowed_object(wide)
    assert allowed.allowed_object is not None
    assert allowed.allowed_object.touch_links == FINGER_LINKS
    assert collision_checker(allowed, 0.0).is_valid(q)
    # but the palm may not touch it: a tall allowed object reaching the palm is a collision
    tall = Box("cube", (0.05, 0.05, 0.3), (0.45, 0.0, 0.15))
    assert not collision_checker(table_scene.with_allowed_object(tall), 0.0).is_valid(q)
    assert collision_checker(table_scene.with_allowed_object(cube), 0.0).is_valid(q)


def test_cylinder_obstacle(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    T = kin.fk(HOME_Q)
    cyl = Cylinder.at("can", 0.03, 0.1, T)
    assert not collision_checker(table_scene.with_obstacles(cyl), 0.0).is_valid(HOME_Q)


def test_check_path_finds_a_thin_obstacle_between_states(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    qa = kin.ik(make_T(TOP_DOWN_R, [0.45, -0.2, 0.1]), HOME_Q).q
    qb = kin.ik(make_T(TOP_DOWN_R, [0.45, 0.2, 0.1]), HOME_Q).q
    wall = Box("wall", (0.2, 0.01, 0.3), (0.45, 0.0, 0.15))
    checker = collision_checker(table_scene.with_obstacles(wall), 0.0)
    assert checker.is_valid(qa) and checker.is_valid(qb)
    coarse = checker.check_path(np.stack([qa, qb]), resolution_rad=10.0)
    assert coarse.ok  # only the end points are checked
    fine = checker.check_path(np.stack([qa, qb]), resolution_rad=0.01)
    assert not fine.ok and fine.first_invalid_segment == 0


def test_planning_scene_rejects_duplicate_names() -> None:
    import pytest

    box = Box("a", (0.1, 0.1, 0.1))
    with pytest.raises(ValueError):
        PlanningScene(obstacles=(box, box))
    with pytest.raises(ValueError):
        Box("bad", (0.1, -0.1, 0.1))
