"""Hand-eye calibration, one control period per tick: the one procedure of the ``Calibrate`` leaf and of
``bt-grasp calibrate`` (which ticks it against the simulated cell).

Plan diverse board views from installation data (``plan_calibration_poses``), then for each view plan and
execute the motion, wait until the arm is still, capture and judge the image (``ViewCollector``), and
finally solve every hand-eye method and keep the most consistent one.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.motion_job import MotionJob, PathFailure, PathFn, Segment
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.seeds import Stream

if TYPE_CHECKING:
    from bt_grasp.perception.calibration import CalibrationRun, ViewCollector

log = logging.getLogger(__name__)

#: the arm counts as still below this joint speed ...
STILL_RAD_S = 5e-3
#: ... for this many consecutive ticks before a capture
STILL_TICKS = 10
#: a capture counts only when the arm moved less than this (rad, any joint) while it was taken: on a real cell (or
#: a twin) the picture takes wall time, and an arm still creeping under STILL_RAD_S pairs a picture with a pose it
#: has left (1e-4 rad is 0.05 mm at half a metre); in simulation nothing moves while a picture is rendered
STILL_DURING_CAPTURE_RAD = 1e-4
#: after this many captures taken while the arm crept, the next one counts anyway (a view is not lost to a servo
#: that never quite rests)
MAX_RECAPTURES = 5


class CalibrationJob:
    """``update()`` returns None while running, the :class:`CalibrationRun` when done, or a sentence on
    failure. ``progress`` says what it is doing; ``visited``/``planned`` count views."""

    def __init__(self, cell: Cell, poses: int) -> None:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        # deferred: OpenCV and scipy come with it; a tree loads and validates without them
        from bt_grasp.perception.calibration import (
            CalibrationSettings,
            ViewCollector,
            nominal_plan,
            plan_calibration_poses,
        )

        self.cell = cell
        self.error: str | None = None
        self.progress = "planning views"
        self.targets: list[NDArray[np.float64]] = []
        self.motion: MotionJob | None = None
        self.settling = False
        self.still = 0
        self.recaptures = 0
        board = cell.board
        if board is None:
            self.error = "no calibration board is mounted in this cell"
            return
        settings = CalibrationSettings(poses=poses, board=board.spec)
        plan = nominal_plan(cell.scene, cell.camera.mount, cell.camera.intrinsics, board.T_nominal_board)
        self.collector: ViewCollector = ViewCollector(plan, settings)
        checker = cell.planner.checker(PlanningScene.from_scene(cell.scene), 0.0)
        try:
            self.targets = plan_calibration_poses(
                plan, cell.kinematics, cell.robot.joint_positions(), settings,
                cell.seeds.generator(Stream.CALIBRATION), collision_free=checker.is_valid,
            )
        except ValueError as exc:
            self.error = str(exc)

    @property
    def planned(self) -> int:
        return len(self.targets)

    @property
    def visited(self) -> int:
        return self.collector.visited if self.error is None else 0

    def cancel(self) -> None:
        if self.motion is not None:
            self.motion.cancel()

    def update(self) -> CalibrationRun | str | None:
        if self.error is not None:
            return self.error
        if self.settling:
            self._settle()
            return None
        if self.motion is None:
            if self.collector.enough or self.visited >= len(self.targets):
                return self._solve()
            self.motion = MotionJob(self.cell, [Segment("to view", self._path_to(self.targets[self.visited]))])
        outcome = self.motion.update()
        if outcome is None:
            self.progress = f"view {self.visited + 1}/{len(self.targets)}: moving ({len(self.collector.views)} kept)"
            return None
        self.motion = None
        if isinstance(outcome, PathFailure):
            self.progress = f"view {self.visited + 1}: {self.collector.unreached()} ({outcome.sentence})"
            return None
        self.settling, self.still = True, 0
        self._settle()
        return None

    def _settle(self) -> None:
        """Wait until the arm is still, then capture and judge the view."""
        speed = float(np.max(np.abs(self.cell.robot.joint_velocities())))
        self.still = self.still + 1 if speed < STILL_RAD_S else 0
        if self.still < STILL_TICKS:
            return
        q = self.cell.robot.joint_positions()
        frame = self.cell.camera.capture()
        crept = float(np.max(np.abs(self.cell.robot.joint_positions() - q)))
        if crept > STILL_DURING_CAPTURE_RAD and self.recaptures < MAX_RECAPTURES:
            self.recaptures += 1
            self.still = 0
            log.info("view %d: the arm moved %.2g rad while its picture was taken; taken again", self.visited + 1,
                     crept)
            return
        self.settling, self.recaptures = False, 0
        if frame is not None:
            self.cell.media.frame(frame, None)
        T_base_tool = self.cell.kinematics.fk_link(q, self.collector.settings.tool_link)
        self.progress = f"view {self.visited + 1}: {self.collector.add(frame, T_base_tool)}"

    def _path_to(self, q_goal: NDArray[np.float64]) -> PathFn:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
            result = self.cell.planner.plan_to_joints(
                q, q_goal, PlanningScene.from_scene(self.cell.scene), self.cell.planner_options
            )
            if not result.ok:
                return PathFailure(FailureReason.PLAN_FAILED, f"{result.status.value}: {result.message}")
            return np.asarray(result.path)

        return compute

    def _solve(self) -> CalibrationRun | str:
        try:
            run = self.collector.solve()
        except ValueError as exc:
            return str(exc)
        self.progress = f"{run.solution.method}: {len(run.views)} views"
        return run
