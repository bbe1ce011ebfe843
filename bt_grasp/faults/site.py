"""Where a fault plan is installed: the run's cell (whose services faults wrap), its tree (whose leaf
entries trigger faults), a physics hook of the simulator and the run's fault random stream."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol

import numpy as np

from bt_grasp.behaviours.services import CameraCalibration, Planner
from bt_grasp.clock import Clock
from bt_grasp.faults.physics import PhysicsHook
from bt_grasp.interfaces import Camera, Robot
from bt_grasp.motion.kinematics import KinematicModel
from bt_grasp.tree.node import BtNode


class FaultableCell(Protocol):
    """The services a fault replaces with a wrapper of the same Protocol (``bt_grasp.behaviours.cell.Cell``)."""

    camera: Camera
    robot: Robot
    planner: Planner
    kinematics: KinematicModel
    calibration: CameraCalibration | None
    clock: Clock


class BlackboardView(Protocol):
    def has(self, key: str) -> bool: ...

    def get(self, key: str) -> object: ...


class FaultTree(Protocol):
    """The tree's nodes (leaves get a pre-tick hook that reports their entries) and its blackboard."""

    @property
    def root_blackboard(self) -> BlackboardView: ...

    def nodes(self) -> Iterable[BtNode]: ...


class FaultSite(Protocol):
    """What ``install_faults`` needs of a run (``bt_grasp.episode.cell_assembly`` provides it)."""

    @property
    def cell(self) -> FaultableCell: ...

    @property
    def tree(self) -> FaultTree: ...

    @property
    def physics(self) -> PhysicsHook: ...

    @property
    def fault_seed_sequence(self) -> np.random.SeedSequence: ...
