"""``tree run --dry --camera SOURCE``: a tree's perception on real (or recorded) frames before the arm moves.

The tree is loaded as a dry run (``bt_grasp.tree.dry_run``: every robot leaf a stand-in) except the perception
leaves of :data:`REAL_LEAVES`, which run for real in a :class:`bt_grasp.behaviours.cell.Cell` holding the camera
source, its calibration and an arm that stays at the home pose (:class:`HomeArm`: stand-ins move nothing):
``Perceive``/``PerceiveAll`` capture one frame per capture, in order (a recording's end is a dropped frame: their
``NO_FRAME``), ``PlanGrasp`` ranks and plans from the home pose; ``SelectObject`` and ``ObjectInfo`` need no robot
and run for real in every dry run. A wrist camera is refused: its frames were taken where the tree's stand-in
``LookAt`` does not move the arm.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.clock import ManualClock
from bt_grasp.errors import InputError
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.interfaces import Mount
from bt_grasp.robot_description import ARM_JOINTS, MAX_OPENING_M
from bt_grasp.sensing.open_source import OpenedSource, open_source
from bt_grasp.sensing.source_spec import SourceKind, SourceSpec

if TYPE_CHECKING:
    from bt_grasp.tree.dry_run import DryRunPlan, DryRunResult
    from bt_grasp.tree.registry import NodeRegistry

#: robot leaves that run for real on the camera's frames (every other robot leaf stays a stand-in)
REAL_LEAVES = frozenset({"Perceive", "PerceiveAll", "PlanGrasp"})


class HomeArm:
    """Implements :class:`bt_grasp.interfaces.Robot`: an arm that stays at ``q_rad`` (a dry run moves nothing)."""

    def __init__(self, q_rad: NDArray[np.float64]) -> None:
        self._q = np.asarray(q_rad, dtype=np.float64).copy()

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(ARM_JOINTS)

    def joint_positions(self) -> NDArray[np.float64]:
        return self._q.copy()

    def joint_velocities(self) -> NDArray[np.float64]:
        return np.zeros(6)

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        return None

    def open_gripper(self) -> None:
        return None

    def close_gripper(self, force_n: float | None = None) -> None:
        return None

    def gripper_width_m(self) -> float:
        return MAX_OPENING_M

    def gripper_target_width_m(self) -> float:
        return MAX_OPENING_M


@dataclass
class CameraDryRun:
    """An open source and the cell the real leaves are set up with; :meth:`close` closes the source."""

    opened: OpenedSource
    cell: object  # bt_grasp.behaviours.cell.Cell (imported when the source is opened)

    def close(self) -> None:
        self.opened.close()


def open_camera_cell(spec: SourceSpec, calibration: Path | None, clock: ManualClock,
                     settings: RealSenseSettings = RealSenseSettings()) -> CameraDryRun:
    """Open the source and build the cell (see the module docstring); InputError for a wrist camera's source."""
    # deferred: the leaves' package (py_trees) only when a tree or its view geometry is needed
    from bt_grasp.behaviours.cell import make_cell

    if spec.kind is SourceKind.SCENE:
        raise InputError("--camera", "is a recording or a device; a scene is run with `bt-grasp run`")
    opened = open_source(spec, calibration, settings)
    if opened.camera.mount == Mount.EYE_IN_HAND:
        opened.close()
        raise InputError("--calibration", "is an eye-in-hand calibration: a dry run's arm stays home, while a wrist "
                         "camera's frames were taken wherever the arm was; check a wrist camera with `bt-grasp "
                         "perceive REC --calibration FILE` (its tool poses beside it)")
    scene = opened.scene
    arm = HomeArm(np.asarray(scene.robot.home_q_rad, dtype=np.float64))
    cell = make_cell(arm, opened.camera, clock, scene, 0, calibration=opened.placer.calibration)
    cell.perception_config = opened.perception_config
    return CameraDryRun(opened, cell)


def dry_run_on_camera(file: Path, registry: NodeRegistry, plan: DryRunPlan, spec: SourceSpec, calibration: Path | None,
                      clock: ManualClock, max_ticks: int, dt_s: float, *, substitutions: Mapping[str, str],
                      entries: Mapping[str, object]) -> DryRunResult:
    """Open the source, load ``file`` as a dry run with :data:`REAL_LEAVES` real and set up with the cell, set the
    blackboard ``entries``, tick it (``bt_grasp.tree.dry_run.run_dry``), close the source."""
    # deferred: the tree package (py_trees) only when a tree runs
    from bt_grasp.tree.dry_run import load_dry, run_dry

    source = open_camera_cell(spec, calibration, clock)
    try:
        tree = load_dry(file, registry, plan, substitutions=substitutions, clock=clock, real=REAL_LEAVES)
        for key, value in entries.items():
            tree.root_blackboard.set(key, value)
        for node in tree.nodes():
            node.setup(cell=source.cell)
        return run_dry(tree, clock, max_ticks, dt_s)
    finally:
        source.close()
