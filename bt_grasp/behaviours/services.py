"""The typed services a robot leaf may use, as Protocols (what the leaf needs, not who provides it).

``bt_grasp.sim``, ``bt_grasp.motion`` and ``bt_grasp.perception`` provide the real ones; fault injectors
wrap them (``bt_grasp.faults``); tests provide stand-ins. Statuses come back as enums (``PlanStatus``,
``IKStatus``), never as text a caller would have to parse.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import RGBDFrame

if TYPE_CHECKING:  # types only: importing motion/perception costs ~1 s (pinocchio, open3d)
    from bt_grasp.behaviours.attempts import Attempt
    from bt_grasp.motion.cartesian import CartesianResult
    from bt_grasp.motion.collision import CollisionChecker
    from bt_grasp.motion.kinematics import KinematicModel
    from bt_grasp.motion.planner import PlannerOptions, PlanResult
    from bt_grasp.motion.planning_scene import PlanningScene
    from bt_grasp.motion.trajectory import Trajectory
    from bt_grasp.perception.results import GraspCandidate, PerceptionResult

__all__ = ["CameraCalibration", "KinematicModel", "MediaSink", "MotionGuard", "NullSink", "Planner", "TrajectoryKind"]

TrajectoryKind = Literal["planned", "executed"]


class Planner(Protocol):
    """Collision-free joint paths for the arm (``bt_grasp.motion.planner.MotionPlanner``)."""

    def plan_to_pose(
        self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
        options: PlannerOptions | None = None,
    ) -> PlanResult: ...

    def plan_to_joints(
        self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: PlanningScene,
        options: PlannerOptions | None = None,
    ) -> PlanResult: ...

    def straight_line(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene
                      ) -> CartesianResult:
        """Joint waypoints moving the tool on a straight line to the goal pose, collision-checked in ``scene``."""
        ...

    def checker(self, scene: PlanningScene, margin_m: float) -> CollisionChecker: ...


class MotionGuard(Protocol):
    """A real cell's safety before motion (``bt_grasp.motion.guard``): every trajectory is checked whole
    before its first sample is sent."""

    def prepare(self, trajectory: Trajectory) -> Trajectory | str:
        """The trajectory as it may be sent (slowed to the cell's caps), or why it may not (one sentence)."""
        ...


class CameraCalibration(Protocol):
    """Where the camera is (``bt_grasp.perception.calibration_file.CalibrationFile``, or a fault's offset)."""

    @property
    def mount(self) -> str: ...

    @property
    def tool_link(self) -> str: ...

    def T_base_camera_at(self, T_base_tool: Mat4 | None = None) -> Mat4:
        """The camera pose in the base frame at capture time (eye-in-hand needs ``T_base_tool``)."""
        ...


class MediaSink(Protocol):
    """Where leaves send what they saw and computed (the run's MCAP recorder, or nothing)."""

    def frame(self, frame: RGBDFrame, T_base_camera: Mat4 | None) -> None: ...

    def perception(self, result: PerceptionResult, T_base_camera: Mat4) -> None: ...

    def grasps(self, candidates: Sequence[GraspCandidate]) -> None: ...

    def trajectory(self, name: str, times_s: NDArray[np.float64], q: NDArray[np.float64],
                   kind: TrajectoryKind) -> None: ...

    def log(self, level: str, name: str, message: str) -> None: ...

    def servo(self, name: str, values: Mapping[str, float | bool | str]) -> None:
        """One control step of a visual-servoing leaf: its measurement, error and command (numbers by name)."""
        ...

    def attempt(self, attempt: Attempt) -> None:
        """A grasp or placement attempt that ended (the log's ``/bt/attempts``)."""
        ...


class NullSink:
    """A MediaSink that keeps nothing (a run without a log, a test)."""

    def frame(self, frame: RGBDFrame, T_base_camera: Mat4 | None) -> None:
        return None

    def perception(self, result: PerceptionResult, T_base_camera: Mat4) -> None:
        return None

    def grasps(self, candidates: Sequence[GraspCandidate]) -> None:
        return None

    def trajectory(self, name: str, times_s: NDArray[np.float64], q: NDArray[np.float64],
                   kind: TrajectoryKind) -> None:
        return None

    def log(self, level: str, name: str, message: str) -> None:
        return None

    def servo(self, name: str, values: Mapping[str, float | bool | str]) -> None:
        return None

    def attempt(self, attempt: Attempt) -> None:
        return None
