"""LoadCalibration and Calibrate: where the camera is, from a file or from a hand-eye calibration run."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from bt_grasp.behaviours.base import HaltCancelsJob, RobotLeaf
from bt_grasp.behaviours.calibration_job import CalibrationJob
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.errors import ConfigError
from bt_grasp.tree.node_api import Status, action, input_port, output_port


@action(
    ports=[
        input_port("file", str, description="calibration YAML written by `bt-grasp calibrate`", required=True),
        output_port("calibration", object, "the loaded calibration", default="{calibration}"),
    ],
    reasons=(FailureReason.CALIBRATION_MISSING,),
    needs_robot=True,
)
class LoadCalibration(RobotLeaf):
    """Load the camera calibration from a file; FAILURE (CALIBRATION_MISSING) when it cannot be used."""

    def update(self) -> Status:
        # deferred: OpenCV comes with it; a tree loads and validates without it
        from bt_grasp.perception.calibration_file import load_calibration

        file = self.ports.get("file", str) or ""
        if not file:
            return self.fail(
                FailureReason.CALIBRATION_MISSING, "no calibration file given (run with --calibration FILE)"
            )
        try:
            calibration = load_calibration(Path(str(file)), mount=self.cell.camera.mount, quote=False)
        except ConfigError as exc:
            return self.fail(FailureReason.CALIBRATION_MISSING, str(exc))
        self.cell.calibration = calibration
        self.ports.set("calibration", calibration)
        self.feedback_message = f"{calibration.mount} calibration from {file} ({calibration.method})"
        return Status.SUCCESS


@action(
    ports=[
        input_port("poses", int, 20, "number of board views to collect (15 to 25)"),
        input_port("file", str, "", "where to write the calibration YAML (empty: nowhere)"),
        output_port("calibration", object, "the solved calibration", default="{calibration}"),
    ],
    reasons=(FailureReason.CALIBRATION_FAILED, FailureReason.PLAN_FAILED, FailureReason.TRACKING_ERROR),
    needs_robot=True,
)
class Calibrate(HaltCancelsJob, RobotLeaf):
    """Hand-eye calibration: move the ChArUco board through diverse views, capture, solve; one view per step."""

    def initialise(self) -> None:
        self.job = CalibrationJob(self.cell, self.ports.require("poses", int))

    def update(self) -> Status:
        outcome = self.job.update()
        self.feedback_message = self.job.progress
        if outcome is None:
            return Status.RUNNING
        if isinstance(outcome, str):
            return self.fail(FailureReason.CALIBRATION_FAILED, outcome)
        self.run = outcome
        self.cell.calibration = outcome.calibration
        self.ports.set("calibration", outcome.calibration)
        file = self.ports.get("file", str) or ""
        if file:
            # deferred: OpenCV comes with it; a tree loads and validates without it
            from bt_grasp.perception.calibration_file import save_calibration

            save_calibration(outcome.calibration, Path(str(file)))
        return Status.SUCCESS


def needs_calibration_board(nodes: Iterable[object]) -> bool:
    """Whether a tree has a leaf that calibrates (so the cell must have a calibration board mounted)."""
    return any(isinstance(node, Calibrate) for node in nodes)
