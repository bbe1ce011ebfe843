"""Perception: RGB-D frames in, typed results out (objects, grasps, hand-eye calibration).

Never imports the simulator or its ground-truth oracle: every pose comes from the images and the
calibration. The behaviour-tree leaves call:

* :func:`perceive` (frame, ``T_base_camera``, config, colour) -> :class:`PerceptionResult`
* :func:`synthesize_grasps` (detection, neighbours, settings) -> :class:`GraspResult`
"""

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
    "Detection",
    "GraspCandidate",
    "GraspResult",
    "GraspSettings",
    "GraspStatus",
    "PerceptionConfig",
    "PerceptionResult",
    "PerceptionStatus",
    "load_perception_config",
    "perceive",
    "synthesize_grasps",
]
