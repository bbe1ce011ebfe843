"""Stand-ins for the robot and camera, stepped by the test (no simulator)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import Cell, make_cell
from bt_grasp.clock import ManualClock
from bt_grasp.motion.cartesian import CartesianResult, CartesianStatus
from bt_grasp.motion.kinematics import IKResult, IKStatus
from bt_grasp.motion.planner import PlanResult, PlanStatus
from bt_grasp.perception.results import Detection
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene.format import Scene


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


class FakeKinematics:
    """IK fails for the first ``failures`` calls, then succeeds (slightly away from the seed)."""

    opening_m = MAX_OPENING_M

    def __init__(self, failures: int = 0) -> None:
        self.failures = failures
        self.calls = 0

    def fk(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        T = np.eye(4)
        T[:3, 3] = q[:3]
        return T

    def fk_link(self, q: NDArray[np.float64], link: str) -> NDArray[np.float64]:
        return self.fk(q)

    def ik(self, T: NDArray[np.float64], q_current: NDArray[np.float64], **kwargs: object) -> IKResult:
        self.calls += 1
        if self.calls <= self.failures:
            return IKResult(IKStatus.UNREACHABLE, q_current, 1.0, 1.0, 0)
        return IKResult(IKStatus.OK, q_current + 0.1, 0.0, 0.0, 1)

    def ik_solutions(self, T: NDArray[np.float64], q_current: NDArray[np.float64], **kwargs: object
                     ) -> tuple[list[NDArray[np.float64]], IKResult]:
        best = self.ik(T, q_current)
        return ([best.q] if best.ok else []), best


class FakePlanner:
    """Plans a two-point joint path; ``statuses`` scripts the outcome of successive calls (then OK), and
    ``descents`` the outcome of successive straight lines (then OK)."""

    def __init__(self, statuses: tuple[PlanStatus, ...] = (),
                 descents: tuple[CartesianStatus, ...] = ()) -> None:
        self.statuses = list(statuses)
        self.descents = list(descents)
        self.pose_calls: list[NDArray[np.float64]] = []
        self.line_calls: list[NDArray[np.float64]] = []

    def straight_line(self, q_start: NDArray[np.float64], T: NDArray[np.float64], scene: object
                      ) -> CartesianResult:
        q = np.asarray(q_start, dtype=float)
        self.line_calls.append(q.copy())
        status = self.descents.pop(0) if self.descents else CartesianStatus.OK
        if status is not CartesianStatus.OK:
            return CartesianResult(status, message="waypoint 18/21 collides: gripper_palm vs object_1 (scripted)")
        return CartesianResult(CartesianStatus.OK, path=np.stack([q, q + 0.05]), fraction=1.0)

    def _result(self, q_start: NDArray[np.float64]) -> PlanResult:
        status = self.statuses.pop(0) if self.statuses else PlanStatus.OK
        if status is not PlanStatus.OK:
            return PlanResult(status=status, message="scripted")
        return PlanResult(status=PlanStatus.OK, path=np.stack([q_start, q_start + 0.2]))

    def plan_to_pose(self, q_start: NDArray[np.float64], T: NDArray[np.float64], scene: object,
                     options: object = None) -> PlanResult:
        self.pose_calls.append(np.asarray(q_start, dtype=float).copy())
        return self._result(np.asarray(q_start, dtype=float))

    def plan_to_joints(self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: object,
                       options: object = None) -> PlanResult:
        return self._result(np.asarray(q_start, dtype=float))

    def checker(self, scene: object, margin_m: float) -> object:
        raise NotImplementedError


def detection(x_m: float = 0.5, y_m: float = 0.0, size_m: float = 0.05, label: str = "red") -> Detection:
    """A box standing on the table (base frame), as Perceive reports one."""
    return Detection(label=label, pixel_box=(0, 0, 10, 10), centroid_base_m=(x_m, y_m, size_m / 2),
                     size_m=(size_m, size_m, size_m), yaw_rad=0.0, point_count=500, confidence=1.0)
