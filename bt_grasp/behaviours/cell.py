"""What robot leaves receive in ``setup(cell=...)``: the hardware and the typed services of one run.

Every field is typed (Protocols for what can be wrapped or stood in for, frozen dataclasses for settings);
a leaf reads ``cell.planner``, ``cell.kinematics``, ... directly, never by a string key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.behaviours.attempts import AttemptMemory
from bt_grasp.behaviours.services import CameraCalibration, MediaSink, MotionGuard, NullSink, Planner
from bt_grasp.clock import Clock
from bt_grasp.interfaces import Camera, Encoder, Robot
from bt_grasp.perception.config import GraspSettings, PerceptionConfig
from bt_grasp.scene.format import Scene
from bt_grasp.seeds import RunSeeds, Stream

if TYPE_CHECKING:
    from bt_grasp.motion.executor import ExecutorOptions
    from bt_grasp.motion.kinematics import KinematicModel
    from bt_grasp.motion.planner import PlannerOptions
    from bt_grasp.motion.trajectory import MotionLimits
    from bt_grasp.perception.calibration import BoardMount


def _kinematics() -> KinematicModel:
    # deferred: pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.kinematics import ArmKinematics

    return ArmKinematics()


def _planner() -> Planner:
    # deferred: OMPL, pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.planner import MotionPlanner

    return MotionPlanner()


def _planner_options() -> PlannerOptions:
    # deferred: OMPL, pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.planner import PlannerOptions

    return PlannerOptions()


def _motion_limits() -> MotionLimits:
    # deferred: ruckig comes with it; a tree loads and validates without it
    from bt_grasp.motion.trajectory import MotionLimits

    return MotionLimits()


def _executor_options() -> ExecutorOptions:
    # deferred: ruckig comes with it; a tree loads and validates without it
    from bt_grasp.motion.executor import ExecutorOptions

    # a grasped object makes the wrist jitter by ~0.01 rad/s at rest: settle on position, not stillness
    return ExecutorOptions(settle_velocity_rad_s=0.03)


def _grasp_settings() -> GraspSettings:
    return GraspSettings()


@dataclass
class Cell:
    """The hardware and services the leaves share during one run.

    ``calibration`` is filled by ``LoadCalibration``/``Calibrate`` (or ``--calibration``); leaves that need
    the camera pose fail with CALIBRATION_MISSING until then. ``board`` is the calibration board mounted in
    the cell (None: no board; ``Calibrate`` fails). Fault injectors replace ``robot``, ``camera``,
    ``planner``, ``kinematics`` and ``calibration`` with wrappers of the same Protocols. A real cell adds ``guard``
    (every trajectory checked before it is sent) and ``motion_clock`` (trajectory time, which the speed slider
    slows; None: ``clock``). ``attempts`` is the run's memory of what it tried (grasps, placements) and how each
    ended, which the leaves consult.
    Build one with :func:`make_cell` (the run's settings) or directly (tests).

    ``perception_latency_s`` is the seam through which perception's delay reaches the tree: a capture's detections
    are handed to the tree that long after the frame's timestamp, on ``clock`` (:meth:`detections_ready_ns`). A
    simulated run takes it from its scene (the world computes in no simulated time, so the delay must be paid
    explicitly); a real cell keeps 0, or its cell file's value: there the time perception takes passes on the
    wall clock by itself, and ``now - frame.stamp_ns`` is the real latency (frame stamps on the cell's clock).
    """

    robot: Robot
    camera: Camera
    clock: Clock
    scene: Scene
    seed: int
    perception_config: PerceptionConfig
    kinematics: KinematicModel = field(default_factory=_kinematics)
    planner: Planner = field(default_factory=_planner)
    planner_options: PlannerOptions = field(default_factory=_planner_options)
    motion_limits: MotionLimits = field(default_factory=_motion_limits)
    executor_options: ExecutorOptions = field(default_factory=_executor_options)
    grasp_settings: GraspSettings = field(default_factory=_grasp_settings)
    calibration: CameraCalibration | None = None
    board: BoardMount | None = None
    media: MediaSink = field(default_factory=NullSink)
    #: the run's memory of its grasp and placement attempts (``bt_grasp.behaviours.attempts``)
    attempts: AttemptMemory = field(default_factory=AttemptMemory)
    workdir: Path = Path(".")
    perception_latency_s: float = 0.0
    #: the conveyors' encoders, by the fixture's name (a belt the scene or cell declares one for)
    encoders: dict[str, Encoder] = field(default_factory=dict)

    def detections_ready_ns(self, frame_stamp_ns: int) -> int:
        """When the detections of a frame stamped ``frame_stamp_ns`` reach the tree (the cell's clock): the
        frame's stamp plus the declared latency, and never before now (0 latency: now, whatever the stamp's
        clock)."""
        now = self.clock.now_ns()
        if self.perception_latency_s <= 0:
            return now
        return max(now, int(frame_stamp_ns) + round(self.perception_latency_s * 1e9))
    guard: MotionGuard | None = None
    motion_clock: Clock | None = None

    @property
    def seeds(self) -> RunSeeds:
        """The run's seed streams (``bt_grasp.seeds``): every random draw a leaf makes comes from one of them."""
        return RunSeeds(self.seed)


def make_cell(
    robot: Robot, camera: Camera, clock: Clock, scene: Scene, seed: int,
    calibration: CameraCalibration | None = None, board: BoardMount | None = None,
    perception_latency_s: float = 0.0,
) -> Cell:
    """A cell with the run's settings: the planner and the kinematics' IK restarts on their streams of the run's
    seed (``bt_grasp.seeds``), perception from the scene; detections delayed by ``perception_latency_s``."""
    # deferred: OMPL, pinocchio and coal come with it; a tree loads and validates without them
    from bt_grasp.motion.kinematics import ArmKinematics, SeededKinematics
    from bt_grasp.motion.planner import PlannerOptions  # deferred: as above

    seeds = RunSeeds(seed)

    return Cell(
        robot=robot,
        camera=camera,
        clock=clock,
        scene=scene,
        seed=seed,
        perception_config=PerceptionConfig.for_scene(scene),
        planner_options=PlannerOptions(seed=seeds.integer(Stream.PLANNER)),
        kinematics=SeededKinematics(ArmKinematics(), seeds.integer(Stream.IK)),
        calibration=calibration,
        board=board,
        perception_latency_s=float(perception_latency_s),
    )
