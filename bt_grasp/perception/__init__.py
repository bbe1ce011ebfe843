"""Perception: RGB-D frames in, typed results out (objects, grasps, hand-eye calibration).

Never imports the simulator or its ground-truth oracle: every pose comes from the images and the
calibration. The behaviour-tree leaves call:

* :func:`perceive` (frame, ``T_base_camera``, config, colour) -> :class:`PerceptionResult`
* :func:`synthesize_grasps` (detection, neighbours, settings) -> :class:`GraspResult`
* :func:`load_calibration` (path, mount) / :func:`save_calibration` (calibration, path)
* :func:`plan_calibration_poses` + :class:`ViewCollector` (the image side of hand-eye calibration)
"""

from bt_grasp.perception.calibration import (
    CalibrationRun,
    CalibrationSettings,
    ViewCollector,
    ViewPlan,
    nominal_plan,
    plan_calibration_poses,
)
from bt_grasp.perception.calibration_file import CalibrationFile, load_calibration, save_calibration
from bt_grasp.perception.config import GraspSettings, PerceptionConfig, load_perception_config
from bt_grasp.perception.grasps import synthesize_grasps
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import (
    Detection,
    GraspCandidate,
    GraspResult,
    GraspStatus,
    PerceptionResult,
    PerceptionStatus,
)

__all__ = [
    "CalibrationFile",
    "CalibrationRun",
    "CalibrationSettings",
    "Detection",
    "GraspCandidate",
    "GraspResult",
    "GraspSettings",
    "GraspStatus",
    "PerceptionConfig",
    "PerceptionResult",
    "PerceptionStatus",
    "ViewCollector",
    "ViewPlan",
    "load_calibration",
    "load_perception_config",
    "nominal_plan",
    "perceive",
    "plan_calibration_poses",
    "save_calibration",
    "synthesize_grasps",
]
