"""Shared fixtures of the motion tests: one arm model per session (building one parses the URDF)."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.motion.kinematics import ArmKinematics

HOME_Q = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


@pytest.fixture(scope="session")
def kin() -> ArmKinematics:
    return ArmKinematics()


@pytest.fixture(scope="session")
def scene_config():  # type: ignore[no-untyped-def]
    from bt_grasp.scene.format import load_scene

    return load_scene("scenes/tabletop.yaml")


@pytest.fixture(scope="session")
def table_scene(scene_config):  # type: ignore[no-untyped-def]
    from bt_grasp.motion.planning_scene import PlanningScene

    return PlanningScene.from_scene(scene_config)


#: a tool pose pointing straight down (tcp z along -z of the base), gripper closing along base y
TOP_DOWN_R = np.diag([1.0, -1.0, -1.0])
