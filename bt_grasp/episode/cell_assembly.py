"""The one place a run's cell is assembled: its devices, the services its leaves share, and every wrapper.

A cell (``bt_grasp.behaviours.cell.Cell``) is what robot leaves receive in ``setup(cell=...)``. Whatever the
devices are (a simulated world's robot and camera, or a real cell's), it is put together here, in this order:

1. the services on the devices (:func:`~bt_grasp.behaviours.cell.make_cell`): the planner seeded from the
   run's seeds, perception settings from the scene, the calibration if one was loaded, the board if mounted;
   a real cell's devices bring more (:class:`RealCellServices`): the robot description with their gripper (the
   kinematics and the planner's collision model), the motion guard and trajectory clock, the speed caps as motion
   limits and grasp synthesis for their gripper;
2. the planning instrument (:class:`~bt_grasp.episode.instruments.TimedPlanner`: counts the run's plans for
   its result; changes nothing);
3. the log's media sink (pictures the leaves hand to the log), when the run is recorded or watched;
4. the fault wrappers (camera, robot, planner, kinematics; ``bt_grasp.faults``), when a fault plan is given
   or an operator may fire faults (an interactive run).

So what ``cell.planner`` is at run time is read here: ``FaultyPlanner(TimedPlanner(MotionPlanner))`` with
faults, ``TimedPlanner(MotionPlanner)`` without.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.behaviours.cell import Cell, make_cell
from bt_grasp.clock import Clock
from bt_grasp.episode.instruments import TimedPlanner
from bt_grasp.interfaces import Camera, Encoder, Robot
from bt_grasp.seeds import Stream

if TYPE_CHECKING:
    from pathlib import Path

    from bt_grasp.behaviours.services import CameraCalibration, MotionGuard
    from bt_grasp.faults.injector import Injector
    from bt_grasp.faults.physics import PhysicsHook
    from bt_grasp.faults.plan import FaultPlan
    from bt_grasp.motion.trajectory import MotionLimits
    from bt_grasp.perception.calibration import BoardMount
    from bt_grasp.perception.config import GraspSettings
    from bt_grasp.recording.writer import RunRecorder
    from bt_grasp.scene.format import Scene
    from bt_grasp.tree.loader import LoadedTree


@dataclass(frozen=True)
class RealCellServices:
    """What a real cell's devices bring to the services: the robot description with its gripper (kinematics and
    collision model), the guard every trajectory passes before it is sent, trajectory time (the speed slider slows
    it), the cell's caps as motion limits and grasp synthesis for its gripper."""

    robot_urdf: Path
    guard: MotionGuard
    motion_clock: Clock
    motion_limits: MotionLimits
    grasp_settings: GraspSettings


@dataclass(frozen=True)
class CellDevices:
    """The devices of a run's cell and the clock they keep time by (a simulated world's, or a real cell's).

    ``perception_latency_s``: how long after a frame's timestamp its detections reach the tree, paid on ``clock``
    (``Cell.detections_ready_ns``). A simulated world's is its scene's (``Scene.latency_s``): its clock stands
    still while perception computes. A real cell's is 0 (or its cell file's ``camera.perception_latency_s``): the
    time perception takes passes on the wall clock by itself."""

    robot: Robot
    camera: Camera
    clock: Clock
    board: BoardMount | None = None  # the calibration board mounted in the cell (None: none)
    perception_latency_s: float = 0.0
    encoders: Mapping[str, Encoder] = field(default_factory=dict)  # conveyors' encoders by fixture name
    real: RealCellServices | None = None  # a real cell's (None: the simulator's, bt_grasp's own gripper)


@dataclass(frozen=True)
class FaultSetting:
    """What the fault wrappers need besides the cell: the plan, the tree whose leaf entries trigger faults,
    the physics hook of the simulator and the run's fault random stream."""

    plan: FaultPlan
    tree: LoadedTree
    physics: PhysicsHook
    seed_sequence: np.random.SeedSequence


@dataclass(frozen=True)
class AssembledCell:
    cell: Cell
    planning: TimedPlanner  # the run's planning statistics (its result reports them)
    injector: Injector | None  # the fault injector, when faults were installed


@dataclass(frozen=True)
class _Site:
    """``bt_grasp.faults.site.FaultSite`` for :func:`~bt_grasp.faults.injector.install_faults`."""

    cell: Cell
    tree: LoadedTree
    physics: PhysicsHook
    fault_seed_sequence: np.random.SeedSequence


def assemble_cell(devices: CellDevices, scene: Scene, seed: int, calibration: CameraCalibration | None, *,
                  recorder: RunRecorder | None = None, now_ns: Callable[[], int] | None = None,
                  faults: FaultSetting | None = None) -> AssembledCell:
    """The run's cell, assembled in the order the module's docstring gives. ``recorder``: the run's log or live
    view (its media sink stamps pictures with ``now_ns``); ``faults``: install the fault wrappers."""
    cell = make_cell(devices.robot, devices.camera, devices.clock, scene, seed, calibration=calibration,
                     board=devices.board, perception_latency_s=devices.perception_latency_s)
    cell.encoders = dict(devices.encoders)
    if devices.real is not None:
        _real_services(cell, devices.real)
    planning = TimedPlanner(cell.planner)
    cell.planner = planning
    if recorder is not None:
        from bt_grasp.episode.media import RecorderSink

        cell.media = RecorderSink(recorder, now_ns or devices.clock.now_ns)
    injector = None
    if faults is not None:
        from bt_grasp.faults.injector import install_faults

        site = _Site(cell, faults.tree, faults.physics, faults.seed_sequence)
        injector = install_faults(faults.plan, site, recorder)
    return AssembledCell(cell, planning, injector)


def _real_services(cell: Cell, real: RealCellServices) -> None:
    from bt_grasp.motion.kinematics import SeededKinematics, default_kinematics
    from bt_grasp.motion.planner import MotionPlanner

    # the gripper's robot description, its IK restarts still on the run's stream (as make_cell seeds them)
    cell.kinematics = SeededKinematics(default_kinematics(urdf_path=real.robot_urdf), cell.seeds.integer(Stream.IK))
    cell.planner = MotionPlanner(urdf_path=real.robot_urdf)
    cell.guard = real.guard
    cell.motion_clock = real.motion_clock
    cell.motion_limits = real.motion_limits
    cell.grasp_settings = real.grasp_settings
    cell.perception_config = cell.perception_config.model_copy(update={"grasp": real.grasp_settings})
