"""Perceive and ObjectVisible: one RGB-D capture through the perception pipeline, in the base frame.

``Perceive`` and ``PerceiveAll`` (objects.py) take ``detector``: ``geometric`` (the default: the point-cloud
pipeline alone) or ``learned`` (a YOLO-OBB model's oriented boxes by class, joined with the point cloud:
``bt_grasp.perception.learned``), and ``model``, the ONNX export ('' = the shipped household model). A literal
``detector="learned"`` with a literal ``model`` is loaded and checked when the tree is loaded: a file that is not an
OBB export, or an ``imgsz`` it does not take, is a load error naming the tree file's line. onnxruntime is imported
only then (or at the first tick, for a model named on the blackboard).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.fixture_mask import without_fixtures
from bt_grasp.behaviours.reasons import PERCEPTION_REASONS, FailureReason
from bt_grasp.detector.kinds import DetectorKind, model_path, parse_detector
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.seeds import Stream
from bt_grasp.tree.exceptions import PortValueError
from bt_grasp.tree.node_api import NodeContext, Status, action, condition, input_port, output_port

if TYPE_CHECKING:
    from bt_grasp.detector.inference import LearnedDetector
    from bt_grasp.perception.results import PerceptionResult

_COLOR = input_port("color", str, "", "target colour name (empty: the most graspable)")
#: the ports that choose the detector (Perceive, PerceiveAll)
DETECTOR_PORTS = (
    input_port("detector", str, DetectorKind.GEOMETRIC.value,
               "what finds the objects: geometric (the point cloud) or learned (a YOLO-OBB model's boxes by class, "
               "joined with the point cloud)", choices=tuple(k.value for k in DetectorKind)),
    input_port("model", str, "",
               "the learned detector's YOLO-OBB ONNX export, relative to the tree file (empty: the shipped household "
               "model)"),
    input_port("imgsz", int, 0, "the input size the model must take, px (0: its own)"),
)


def camera_pose(cell: Cell) -> NDArray[np.float64] | None:
    """T_base_camera now, from the calibration (eye-in-hand composes it with the arm's forward kinematics)."""
    calibration = cell.calibration
    if calibration is None:
        return None
    if calibration.mount == Mount.EYE_TO_HAND:
        return np.asarray(calibration.T_base_camera_at(None), dtype=float)
    T_base_tool = cell.kinematics.fk_link(cell.robot.joint_positions(), calibration.tool_link)
    return np.asarray(calibration.T_base_camera_at(T_base_tool), dtype=float)


class DetectorLeaf(RobotLeaf):
    """A leaf that perceives with the detector its ports name (``DETECTOR_PORTS``); keeps each learned model it
    loaded (one onnxruntime session per model and input size)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self._models: dict[tuple[Path, int], LearnedDetector] = {}
        #: the learned detector the tree file names literally, loaded and checked with the tree (else None)
        self.literal_model: LearnedDetector | None = None
        literal = all(self.ports.key(p) is None for p in ("detector", "model", "imgsz"))
        if literal and parse_detector(self.ports.require("detector", str)) is DetectorKind.LEARNED:
            # deferred: OpenCV comes with it; a tree loads and validates without it
            from bt_grasp.detector.model import ModelError

            model, imgsz = self.ports.require("model", str), self.ports.require("imgsz", int)
            try:
                self.literal_model = self._model(model, imgsz, True)
            except ModelError as exc:
                raise PortValueError(f"port 'model': {exc.message}") from None

    def _model(self, text: str, imgsz: int, from_tree: bool) -> LearnedDetector:
        # deferred: OpenCV comes with it (onnxruntime once a model runs); a tree loads and validates without it
        from bt_grasp.detector.inference import LearnedDetector

        path = model_path(text, self.ctx.source if from_tree else None)
        key = (path, imgsz)
        if key not in self._models:
            # deferred: Open3D and OpenCV come with it; a tree loads and validates without them
            from bt_grasp.perception.learned import TENTATIVE_SCORE

            # decoded down to the tentative score: the join decides what a box under the sure score may name
            self._models[key] = LearnedDetector.load(path, imgsz=imgsz or None, conf=TENTATIVE_SCORE)
        return self._models[key]

    def detector_now(self) -> LearnedDetector | Status | None:
        """The learned detector the ports name now (a model named on the blackboard is loaded on first use; a
        bad one is a :class:`bt_grasp.detector.model.ModelError`: exit 2), None for the geometric detector, or
        the FAILURE status for a detector name that is neither."""
        text = self.ports.get("detector", str) or ""
        kind = parse_detector(text)
        if kind is None:
            return self.fail(FailureReason.BAD_INPUT, f"detector must be geometric or learned, not '{text}'")
        if kind is DetectorKind.GEOMETRIC:
            return None
        if self.literal_model is not None:
            return self.literal_model
        model = self.ports.get("model", str) or ""
        return self._model(model, self.ports.require("imgsz", int), self.ports.key("model") is None)


def perceive_once(leaf: RobotLeaf, color: str | None, accept_empty: bool = False,
                  detector: LearnedDetector | None = None) -> Status | PerceptionResult:
    """Capture + pipeline: the leaf's FAILURE status, or the (successful) PerceptionResult. With
    ``accept_empty`` a table with nothing on it is a result (no detections), not a failure, and so (with a
    learned ``detector``) is a table whose objects the detector named none of."""
    # deferred: Open3D and OpenCV come with it; a tree loads and validates without them
    from bt_grasp.perception.pipeline import perceive

    cell = leaf.cell
    T_base_camera = camera_pose(cell)
    if T_base_camera is None:
        return leaf.fail(FailureReason.CALIBRATION_MISSING, "no camera calibration loaded")
    frame: RGBDFrame | None = cell.camera.capture()
    if frame is None:
        return leaf.fail(FailureReason.NO_FRAME, "the camera returned no frame")
    cell.media.frame(frame, T_base_camera)
    config = cell.perception_config
    if color and color not in config.color.ranges:
        known = ", ".join(config.color.ranges)
        return leaf.fail(FailureReason.BAD_INPUT, f"unknown colour '{color}'; known: {known}")
    if detector is None:
        result = perceive(frame, T_base_camera, config, color or None, seed=cell.seeds.integer(Stream.PERCEPTION))
    else:
        # deferred: Open3D and OpenCV come with it; a tree loads and validates without them
        from bt_grasp.perception.learned import join_boxes

        found = detector.detect(frame.color)
        seen = perceive(frame, T_base_camera, config, seed=cell.seeds.integer(Stream.PERCEPTION))
        result = join_boxes(seen, found.boxes, frame, T_base_camera, config,
                            color or None)
        result = replace(result, timings_ms={**result.timings_ms, "detector_network": found.network_ms,
                                             "detector_decode": found.decode_ms})
    result = without_fixtures(result, cell.scene)
    cell.media.perception(result, T_base_camera)
    if accept_empty and (result.status.value == "no_objects" or (detector is not None and result.others)):
        return result
    if not result.ok:
        return leaf.fail(FailureReason.NO_DETECTION, f"{result.status.value}: {result.message}")
    return result


@action(
    ports=[
        _COLOR,
        output_port("target", object, "the chosen detection", default="{target}"),
        output_port("objects", object, "every object seen (for clearance)", default="{objects}"),
        *DETECTOR_PORTS,
    ],
    reasons=PERCEPTION_REASONS,
    needs_robot=True,
)
class Perceive(DetectorLeaf):
    """Capture one RGB-D frame and find the target object on the table (base frame, via the calibration).

    With ``detector="learned"`` the target is the object the model's best-scoring box named (of ``color``,
    when given); its ``class_name``/``class_score`` say what and how sure."""

    def update(self) -> Status:
        detector = self.detector_now()
        if isinstance(detector, Status):
            return detector
        result = perceive_once(self, self.ports.get("color", str) or "", detector=detector)
        if isinstance(result, Status):
            return result
        best = result.best
        if best is None:
            return self.fail(FailureReason.NO_DETECTION, "the pipeline succeeded with no detection")
        self.ports.set("target", best)
        self.ports.set("objects", tuple(result.others))
        c = best.centroid_base_m
        named = f"{best.class_name} ({best.class_score:.2f}) " if best.class_name else ""
        self.feedback_message = (
            f"{named}{best.label} at ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m, yaw {np.rad2deg(best.yaw_rad):.1f} deg"
        )
        return Status.SUCCESS


@condition(ports=[_COLOR], reasons=PERCEPTION_REASONS, needs_robot=True)
class ObjectVisible(RobotLeaf):
    """SUCCESS when the camera sees an object (of the colour) on the table."""

    def update(self) -> Status:
        result = perceive_once(self, self.ports.get("color", str) or "")
        if isinstance(result, Status):
            return result
        self.feedback_message = f"{len(result.detections)} object(s) visible"
        return Status.SUCCESS
