"""Stand-ins for the robot and camera, stepped by the test (no simulator)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import Cell, make_cell
from bt_grasp.clock import ManualClock
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene_config import Scene


class FakeRobot:
    """Fingers move 5 mm per step towards the target, stopping on an object of ``object_width_m``."""

    def __init__(self, object_width_m: float = 0.0) -> None:
        self.object_width_m = object_width_m
        self.width = MAX_OPENING_M
        self.target = MAX_OPENING_M
        self.q = np.zeros(6)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(f"j{i}" for i in range(6))

    def joint_positions(self) -> NDArray[np.float64]:
        return self.q.copy()

    def joint_velocities(self) -> NDArray[np.float64]:
        return np.zeros(6)

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        self.q = np.asarray(q_rad, dtype=float)

    def open_gripper(self) -> None:
        self.target = MAX_OPENING_M

    def close_gripper(self, force_n: float | None = None) -> None:
        self.target = 0.0

    def gripper_width_m(self) -> float:
        return self.width

    def gripper_target_width_m(self) -> float:
        return self.target

    def step(self) -> None:
        stop = self.object_width_m if self.target < self.width else self.target
        goal = max(self.target, stop) if self.target < self.width else self.target
        self.width += float(np.clip(goal - self.width, -0.005, 0.005))


class FakeCamera:
    mount = "eye-to-hand"

    def capture(self) -> None:
        return None


def fake_cell(robot: FakeRobot, clock: ManualClock) -> Cell:
    return make_cell(robot, FakeCamera(), clock, Scene(), seed=0)  # type: ignore[arg-type]
