"""One frame through the perception pipeline and grasp ranking, as a tree's leaves do it (no motion).

:class:`Perceiver` makes the calls ``PerceiveAll`` makes (``bt_grasp.behaviours.perceive.perceive_once``: the
pipeline, the learned detector's boxes joined with it, fixtures removed) and, for every object seen, the ranking
``PlanGrasp`` starts from (``bt_grasp.perception.antipodal.rank_grasps`` with the same settings, the same reach test
from the scene's home pose and the camera's position as viewpoint), so a tree run on the same frame chooses from the
same objects and tries the same grasps first. Without a calibration the pipeline runs in the table frame the frame
shows and nothing is tested for reach (no robot is known).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.kinds import DetectorKind, model_path
from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.perception.config import GraspSettings, PerceptionConfig
from bt_grasp.perception.results import Detection, GraspResult, GraspStatus, PerceptionResult, PerceptionStatus
from bt_grasp.scene.format import Scene
from bt_grasp.seeds import RunSeeds, Stream
from bt_grasp.sensing.placement import Placement

if TYPE_CHECKING:
    from bt_grasp.detector.inference import LearnedDetector

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FramePerception:
    """What one frame showed: the pipeline's result (in the pipeline's frame) and, for each of ``result.others`` in
    order, its ranked grasps. ``placement`` None: the frame could not be placed (no calibration and no table)."""

    frame: RGBDFrame
    placement: Placement | None
    result: PerceptionResult
    grasps: tuple[GraspResult, ...]


class Perceiver:
    """Perceives frames with one detector and one set of settings (see the module docstring)."""

    def __init__(self, config: PerceptionConfig, scene: Scene, detector: DetectorKind = DetectorKind.GEOMETRIC,
                 grasp_settings: GraspSettings | None = None, seed: int = 0) -> None:
        """``seed``: the run seed whose perception, grasp and IK streams the pipeline draws from (``bt_grasp.seeds``),
        as a run with that seed does: a tree's dry run on the same frames with the same seed ranks the same grasps."""
        self.config = config
        self.seeds = RunSeeds(seed)
        self.scene = scene
        self.detector_kind = detector
        self.grasp_settings = grasp_settings or GraspSettings()
        self._learned: LearnedDetector | None = None
        if detector is DetectorKind.LEARNED:
            # deferred: onnxruntime only for the learned detector
            from bt_grasp.detector.inference import LearnedDetector

            # deferred: open3d (~1 s) only when a frame is perceived
            from bt_grasp.perception.learned import TENTATIVE_SCORE

            # as DetectorLeaf loads the shipped model: decoded down to the tentative score
            self._learned = LearnedDetector.load(model_path("", None), imgsz=None, conf=TENTATIVE_SCORE)
        self._q_home = np.asarray(scene.robot.home_q_rad, dtype=np.float64)
        # deferred: open3d (~1 s) only when a frame is perceived
        from bt_grasp.perception.camera_frame import table_config

        #: the settings without a calibration: the region of interest around the table frame's origin
        self._table_config = table_config(config)

    def perceive(self, frame: RGBDFrame, placement: Placement | None) -> FramePerception:
        if placement is None:
            result = PerceptionResult(PerceptionStatus.NO_POINTS, message="no table plane in the frame (no "
                                      "calibration: the frame itself must show the table)")
            return FramePerception(frame, None, result, ())
        config = self.config if placement.calibrated else self._table_config
        result = self._objects(frame, placement.T_pipeline_camera, config)
        grasps = tuple(self._grasps(det, result, placement) for det in result.others)
        return FramePerception(frame, placement, result, grasps)

    def _objects(self, frame: RGBDFrame, T: Mat4, config: PerceptionConfig) -> PerceptionResult:
        # deferred: the leaves' package (py_trees) only when a tree or its view geometry is needed
        from bt_grasp.behaviours.fixture_mask import without_fixtures

        # deferred: open3d (~1 s) only when a frame is perceived
        from bt_grasp.perception.pipeline import perceive

        if self._learned is None:
            result = perceive(frame, T, config, None, seed=self.seeds.integer(Stream.PERCEPTION))
        else:
            # deferred: open3d (~1 s) only when a frame is perceived
            from bt_grasp.perception.learned import join_boxes

            found = self._learned.detect(frame.color)
            seen = perceive(frame, T, config, seed=self.seeds.integer(Stream.PERCEPTION))
            result = join_boxes(seen, found.boxes, frame, T, config, None)
            result = replace(result, timings_ms={**result.timings_ms, "detector_network": found.network_ms,
                                                 "detector_decode": found.decode_ms})
        return without_fixtures(result, self.scene)

    def _grasps(self, target: object, result: PerceptionResult, placement: Placement) -> GraspResult:
        # deferred: open3d (~1 s) only when a frame is perceived
        from bt_grasp.perception.antipodal import rank_grasps

        assert isinstance(target, Detection)
        if not placement.calibrated:
            return rank_grasps(target, result.others, self.grasp_settings, seed=self.seeds.integer(Stream.GRASPS),
                               viewpoint_base_m=tuple(float(v) for v in placement.T_pipeline_camera[:3, 3]))
        # deferred: pinocchio and OMPL only when grasps are tested for reach or planned
        from bt_grasp.motion.planning_scene import fixture_boxes

        fixtures = [(box.T_base_shape, box.size_m) for box in fixture_boxes(self.scene)]
        viewpoint = tuple(float(v) for v in placement.T_pipeline_camera[:3, 3])
        found = rank_grasps(target, result.others, self.grasp_settings, reachable=self._reachable,
                            seed=self.seeds.integer(Stream.GRASPS), fixtures=fixtures, viewpoint_base_m=viewpoint)
        if not found.ok and found.status is not GraspStatus.OK:
            log.info("no grasp of %s: %s", target.label, found.message)
        return found

    def _reachable(self, T_grasp: NDArray[np.float64], T_pregrasp: NDArray[np.float64]) -> bool:
        """PlanGrasp's reach test from the home pose: the pre-grasp, then the grasp from there, have IK solutions."""
        # deferred: pinocchio and OMPL only when grasps are tested for reach or planned
        from bt_grasp.motion.kinematics import SeededKinematics, default_kinematics

        kin = SeededKinematics(default_kinematics(), self.seeds.integer(Stream.IK))  # as the run's cell.kinematics
        pre = kin.ik(T_pregrasp, self._q_home)
        return bool(pre.ok and kin.ik(T_grasp, pre.q).ok)
