"""Perception: RGB-D frames in, typed results out (objects, grasps, hand-eye calibration).

Never imports the simulator or its ground-truth oracle: every pose comes from the images and the
calibration. The behaviour-tree leaves call:

* :func:`perceive` (frame, ``T_base_camera``, config, colour) -> :class:`PerceptionResult`
* :func:`synthesize_grasps` (detection, neighbours, settings) -> :class:`GraspResult`
* :func:`load_calibration` (path, mount) / :func:`save_calibration` (calibration, path)
* :func:`plan_calibration_poses` + :class:`ViewCollector` (the image side of hand-eye calibration)
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from bt_grasp.process.slim_imports import defer_unused_submodules

# open3d (cloud.py, segment.py) would load plotly and dash for drawing helpers nothing here calls (issue 27)
defer_unused_submodules()

if TYPE_CHECKING:
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

#: name -> the module defining it; imported on first use (the pipeline loads open3d: ~1 s)
_EXPORTS = {
    "CalibrationRun": "bt_grasp.perception.calibration",
    "CalibrationSettings": "bt_grasp.perception.calibration",
    "ViewCollector": "bt_grasp.perception.calibration",
    "ViewPlan": "bt_grasp.perception.calibration",
    "nominal_plan": "bt_grasp.perception.calibration",
    "plan_calibration_poses": "bt_grasp.perception.calibration",
    "CalibrationFile": "bt_grasp.perception.calibration_file",
    "load_calibration": "bt_grasp.perception.calibration_file",
    "save_calibration": "bt_grasp.perception.calibration_file",
    "GraspSettings": "bt_grasp.perception.config",
    "PerceptionConfig": "bt_grasp.perception.config",
    "load_perception_config": "bt_grasp.perception.config",
    "synthesize_grasps": "bt_grasp.perception.grasps",
    "perceive": "bt_grasp.perception.pipeline",
    "Detection": "bt_grasp.perception.results",
    "GraspCandidate": "bt_grasp.perception.results",
    "GraspResult": "bt_grasp.perception.results",
    "GraspStatus": "bt_grasp.perception.results",
    "PerceptionResult": "bt_grasp.perception.results",
    "PerceptionStatus": "bt_grasp.perception.results",
}


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)

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
