"""Perceive and ObjectVisible: one RGB-D capture through the perception pipeline, in the base frame."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from py_trees.common import Status

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.fixture_mask import without_fixtures
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.tree.registry import NodeKind, PortDirection, PortSpec, leaf

if TYPE_CHECKING:
    from bt_grasp.perception.results import PerceptionResult

_COLOR = PortSpec("color", PortDirection.INPUT, str, "", "target colour name (empty: the most graspable)")


def camera_pose(cell: Cell) -> NDArray[np.float64] | None:
    """T_base_camera now, from the calibration (eye-in-hand composes it with the arm's forward kinematics)."""
    calibration = cell.calibration
    if calibration is None:
        return None
    if calibration.mount == Mount.EYE_TO_HAND:
        return np.asarray(calibration.T_base_camera_at(None), dtype=float)
    T_base_tool = cell.kinematics.fk_link(cell.robot.joint_positions(), calibration.tool_link)
    return np.asarray(calibration.T_base_camera_at(T_base_tool), dtype=float)


def perceive_once(leaf: RobotLeaf, color: str | None, accept_empty: bool = False) -> Status | PerceptionResult:
    """Capture + pipeline: the leaf's FAILURE status, or the (successful) PerceptionResult. With
    ``accept_empty`` a table with nothing on it is a result (no detections), not a failure."""
    from bt_grasp.perception.pipeline import perceive

    cell = leaf.cell
    T_base_camera = camera_pose(cell)
    if T_base_camera is None:
        return leaf.failed(FailureReason.CALIBRATION_MISSING, "no camera calibration loaded")
    frame: RGBDFrame | None = cell.camera.capture()
    if frame is None:
        return leaf.failed(FailureReason.NO_FRAME, "the camera returned no frame")
    cell.media.frame(frame, T_base_camera)
    config = cell.perception_config
    if color and color not in config.color.ranges:
        known = ", ".join(config.color.ranges)
        return leaf.failed(FailureReason.BAD_INPUT, f"unknown colour '{color}'; known: {known}")
    result = without_fixtures(perceive(frame, T_base_camera, config, color or None), cell.scene)
    cell.media.perception(result, T_base_camera)
    if accept_empty and result.status.value == "no_objects":
        return result
    if not result.ok:
        return leaf.failed(FailureReason.NO_DETECTION, f"{result.status.value}: {result.message}")
    return result


@leaf(
    None,
    name="Perceive",
    ports=[
        _COLOR,
        PortSpec("target", PortDirection.OUTPUT, object, "{target}", "the chosen detection"),
        PortSpec("objects", PortDirection.OUTPUT, object, "{objects}", "every object seen (for clearance)"),
    ],
    needs_robot=True,
)
class Perceive(RobotLeaf):
    """Capture one RGB-D frame and find the target object on the table (base frame, via the calibration)."""

    def update(self) -> Status:
        result = perceive_once(self, self.input_str("color"))
        if isinstance(result, Status):
            return result
        best = result.best
        if best is None:
            return self.failed(FailureReason.NO_DETECTION, "the pipeline succeeded with no detection")
        self.ports.set("target", best)
        self.ports.set("objects", tuple(result.others))
        c = best.centroid_base_m
        self.feedback_message = (
            f"{best.label} at ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m, yaw {np.rad2deg(best.yaw_rad):.1f} deg"
        )
        return Status.SUCCESS


@leaf(None, name="ObjectVisible", kind=NodeKind.CONDITION, ports=[_COLOR], needs_robot=True)
class ObjectVisible(RobotLeaf):
    """SUCCESS when the camera sees an object (of the colour) on the table."""

    def update(self) -> Status:
        result = perceive_once(self, self.input_str("color"))
        if isinstance(result, Status):
            return result
        self.feedback_message = f"{len(result.detections)} object(s) visible"
        return Status.SUCCESS
