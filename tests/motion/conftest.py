"""Shared fixtures of the motion tests: one arm model per session (building one parses the URDF)."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.motion.kinematics import ArmKinematics

HOME_Q = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


@pytest.fixture(scope="session")
def kin() -> ArmKinematics:
    return ArmKinematics()
