"""Hand-eye calibration as a job of one control period per tick (for the ``Calibrate`` leaf).

The same steps as :func:`bt_grasp.perception.calibration.run_calibration`, split across ticks: plan the
views, then for each view plan and execute the motion, wait until the arm is still, capture, detect the
ChArUco board, and finally solve every hand-eye method and keep the most consistent one.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.motion_job import MotionJob, PathFailure, Segment

log = logging.getLogger(__name__)

_STILL_RAD_S = 5e-3
_STILL_TICKS = 10


class CalibrationJob:
    """``update()`` returns None while running, the CalibrationFile when done, or a sentence on failure."""

    def __init__(self, cell: Cell, poses: int) -> None:
        from bt_grasp.motion.planning_scene import PlanningScene
        from bt_grasp.perception.calibration import CalibrationSettings, nominal_plan, plan_calibration_poses

        self.cell = cell
        board = cell.board
        self.error: str | None = None
        self.progress = "planning views"
        self.views: list[Any] = []
        self.visited = 0
        self.motion: MotionJob | None = None
        self.still = 0
        if board is None:
            self.error = "no calibration board is mounted in this cell"
            return
        self.settings = CalibrationSettings(poses=poses, board=board.spec)
        self.plan = nominal_plan(cell.scene, cell.camera.mount, cell.camera.intrinsics, board.T_nominal_board)
        kin = cell.kinematics
        checker = cell.planner.checker(PlanningScene.from_scene(cell.scene), 0.0)
        try:
            self.targets = plan_calibration_poses(
                self.plan, kin, cell.robot.joint_positions(), self.settings,
                np.random.default_rng(cell.seed), collision_free=checker.is_valid,
            )
        except ValueError as exc:
            self.error = str(exc)

    def cancel(self) -> None:
        if self.motion is not None:
            self.motion.cancel()

    def update(self) -> Any:
        if self.error is not None:
            return self.error
        if len(self.views) >= self.settings.poses or (self.visited >= len(self.targets) and self.motion is None):
            return self._solve()
        if self.motion is None:
            self.motion = MotionJob(self.cell, [Segment("to view", self._path_to(self.targets[self.visited]))])
            self.visited += 1
            self.still = 0
        outcome = self.motion.update()
        if outcome is None:
            self.progress = f"view {self.visited}/{len(self.targets)}: moving ({len(self.views)} accepted)"
            return None
        if isinstance(outcome, PathFailure):
            self.motion = None
            self.progress = f"view {self.visited}: {outcome.sentence}"
            return None
        speed = float(np.max(np.abs(self.cell.robot.joint_velocities())))
        self.still = self.still + 1 if speed < _STILL_RAD_S else 0
        if self.still < _STILL_TICKS:
            self.motion.index = len(self.motion.segments)  # done moving: wait for stillness
            return None
        self.motion = None
        self._capture()
        return None

    def _path_to(self, q_goal: NDArray[np.float64]) -> Any:
        from bt_grasp.motion.planning_scene import PlanningScene

        def compute(q: NDArray[np.float64]) -> NDArray[np.float64] | PathFailure:
            result = self.cell.planner.plan_to_joints(
                q, q_goal, PlanningScene.from_scene(self.cell.scene), self.cell.planner_options
            )
            if not result.ok:
                from bt_grasp.behaviours.reasons import FailureReason

                return PathFailure(FailureReason.PLAN_FAILED, f"{result.status.value}: {result.message}")
            return np.asarray(result.path)

        return compute

    def _capture(self) -> None:
        from bt_grasp.perception.charuco import corner_object_points, detect_board
        from bt_grasp.perception.handeye import View

        frame = self.cell.camera.capture()
        if frame is None:
            self.progress = f"view {self.visited}: no frame"
            return
        self.cell.media.frame(frame, None)
        s = self.settings
        obs = detect_board(frame.color, frame.intrinsics, s.board, s.min_corners)
        if obs.T_camera_board is None or obs.reprojection_px > s.max_reprojection_px:
            self.progress = f"view {self.visited}: {obs.n_corners} corners, rejected"
            return
        q = self.cell.robot.joint_positions()
        T_base_tool = self.cell.kinematics.fk_link(q, s.tool_link)
        points = corner_object_points(s.board)[obs.corner_ids]
        self.views.append(View(T_base_tool, obs.T_camera_board, obs.corner_ids, obs.corners_px, points))
        self.progress = f"view {self.visited}: {obs.n_corners} corners, {obs.reprojection_px:.2f} px"

    def _solve(self) -> Any:
        from bt_grasp.perception.calibration import _board_outline
        from bt_grasp.perception.calibration_file import make_calibration
        from bt_grasp.perception.handeye import EYE_TO_HAND, solve_hand_eye

        if len(self.views) < 3:
            return f"only {len(self.views)} usable views of the board out of {self.visited} visited"
        mount = self.plan.mount
        solution = solve_hand_eye(mount, self.views, self.plan.intrinsics, _board_outline(self.settings.board))
        parent = "base_link" if mount == EYE_TO_HAND else self.settings.tool_link
        residuals = {name: r.as_dict() for name, r in solution.per_method.items()}
        calibration = make_calibration(
            mount, solution.X, parent, solution.method, len(self.views), residuals, self.plan.intrinsics,
            self.settings.board,
        )
        self.progress = f"{solution.method}: {len(self.views)} views"
        log.info("calibrated %s with %s from %d views", mount, solution.method, len(self.views))
        return calibration
