"""Straight-line tool segments: the tcp stays on the line; refusals are values."""

from __future__ import annotations

import numpy as np

from bt_grasp.geometry import make_T, pose_error
from bt_grasp.motion.cartesian import (
    CartesianOptions,
    CartesianStatus,
    cartesian_path,
    offset_along_tool_z,
    offset_in_base,
)
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.planning_scene import Box, PlanningScene
from tests.motion.conftest import HOME_Q, TOP_DOWN_R


def _pregrasp(kin: ArmKinematics, xyz: list[float]) -> tuple[np.ndarray, np.ndarray]:
    T = make_T(TOP_DOWN_R, xyz)
    return kin.ik(T, HOME_Q).q, T


def test_descent_stays_on_the_line(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.5, 0.05, 0.15])
    T_goal = offset_along_tool_z(T0, 0.12)  # tool z points down: 12 cm down
    assert abs(T_goal[2, 3] - 0.03) < 1e-12
    result = cartesian_path(q0, T_goal, table_scene)
    assert result.status is CartesianStatus.OK, result.message
    assert result.fraction == 1.0
    for q in result.path:
        p = kin.fk(q)[:3, 3]
        assert abs(p[0] - 0.5) < 1e-4 and abs(p[1] - 0.05) < 1e-4
        assert pose_error(kin.fk(q), T0)[1] < 1e-3
    assert pose_error(kin.fk(result.path[-1]), T_goal)[0] < 1e-4
    assert np.max(np.abs(np.diff(result.path, axis=0))) <= CartesianOptions().max_joint_step_rad


def test_lift_in_base_frame(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.45, -0.1, 0.03])
    result = cartesian_path(q0, offset_in_base(T0, [0, 0, 0.15]), table_scene)
    assert result.ok, result.message
    assert abs(kin.fk(result.path[-1])[2, 3] - 0.18) < 1e-4


def test_descent_into_an_obstacle_is_refused(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.5, 0.0, 0.2])
    block = Box("block", (0.1, 0.1, 0.1), (0.5, 0.0, 0.05))
    result = cartesian_path(q0, offset_along_tool_z(T0, 0.15), table_scene.with_obstacles(block))
    assert result.status is CartesianStatus.COLLISION
    assert 0.0 < result.fraction < 1.0


def test_descent_onto_the_allowed_object_is_accepted(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.5, 0.0, 0.15])
    cube = Box("cube", (0.05, 0.09, 0.05), (0.5, 0.0, 0.025))  # wider than the open fingers: they touch it
    T_goal = offset_along_tool_z(T0, 0.125)
    assert cartesian_path(q0, T_goal, table_scene.with_obstacles(cube)).status is CartesianStatus.COLLISION
    assert cartesian_path(q0, T_goal, table_scene.with_allowed_object(cube)).ok


def test_unreachable_line_is_refused(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.5, 0.0, 0.2])
    result = cartesian_path(q0, offset_in_base(T0, [1.5, 0, 0]), table_scene)
    assert result.status is CartesianStatus.UNREACHABLE
    assert 0.0 < result.fraction < 1.0


def test_tight_joint_step_bound_is_refused(kin: ArmKinematics, table_scene: PlanningScene) -> None:
    q0, T0 = _pregrasp(kin, [0.5, 0.0, 0.2])
    result = cartesian_path(q0, offset_in_base(T0, [0, 0.3, 0]), table_scene,
                            CartesianOptions(step_m=0.05, max_joint_step_rad=0.01))
    assert result.status is CartesianStatus.JOINT_JUMP


def test_bad_input(table_scene: PlanningScene) -> None:
    assert cartesian_path(HOME_Q, np.full((4, 4), np.nan), table_scene).status is CartesianStatus.INVALID_INPUT
