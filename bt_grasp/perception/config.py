"""Perception settings: a strict, frozen model with documented units, loadable from a user's YAML file.

Every field has a default that works for the simulated D435 over the tabletop; a file overrides only what
it names (unknown keys are errors naming the file and line, like every bt_grasp config file).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field, field_validator

from bt_grasp.files.config import StrictModel, load_model
from bt_grasp.geometry import inv, transform_points
from bt_grasp.robot_description import MAX_OPENING_M, TCP_TO_FINGERTIP_M
from bt_grasp.scene.format import Scene

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Range = tuple[float, float]
Hue = Annotated[int, Field(ge=0, le=180)]
Byte = Annotated[int, Field(ge=0, le=255)]


class HsvRange(StrictModel):
    """One box in OpenCV's HSV space (H in 0..180, S and V in 0..255). ``h_min > h_max`` wraps around 0 (red)."""

    h_min: Hue
    h_max: Hue
    s_min: Byte = 0
    s_max: Byte = 255
    v_min: Byte = 0
    v_max: Byte = 255


#: default HSV boxes, measured on the simulated D435 images of the scene colours (see docs/perception.md)
DEFAULT_COLORS: dict[str, tuple[HsvRange, ...]] = {
    "red": (HsvRange(h_min=170, h_max=8, s_min=110, v_min=70),),
    "orange": (HsvRange(h_min=12, h_max=23, s_min=120, v_min=70),),
    "yellow": (HsvRange(h_min=24, h_max=38, s_min=110, v_min=70),),
    "green": (HsvRange(h_min=45, h_max=85, s_min=90, v_min=60),),
    "blue": (HsvRange(h_min=100, h_max=128, s_min=100, v_min=60),),
    "purple": (HsvRange(h_min=132, h_max=160, s_min=90, v_min=60),),
    "white": (HsvRange(h_min=0, h_max=180, s_min=0, s_max=30, v_min=180),),
    "grey": (HsvRange(h_min=0, h_max=180, s_min=0, s_max=30, v_min=100, v_max=179),),
    "black": (HsvRange(h_min=0, h_max=180, s_min=0, s_max=80, v_min=0, v_max=80),),
}


class RegionOfInterest(StrictModel):
    """Axis-aligned box in the robot BASE frame where objects may be, metres."""

    x_m: Range = (0.25, 0.75)
    y_m: Range = (-0.35, 0.35)
    z_m: Range = (-0.03, 0.30)  # include a little of the table below the top (for the plane fit)

    @field_validator("x_m", "y_m", "z_m")
    @classmethod
    def _ordered(cls, value: Range) -> Range:
        if value[0] >= value[1]:
            raise ValueError("a range is [low, high] with low < high")
        return value


class CloudSettings(StrictModel):
    min_depth_m: PositiveFloat = 0.2  # nearer depth readings are ignored
    max_depth_m: PositiveFloat = 2.5  # farther depth readings are ignored
    voxel_m: PositiveFloat = 0.004  # voxel size of the downsampled cloud
    outlier_neighbors: Annotated[int, Field(ge=2)] = 12  # statistical outlier removal: neighbours
    outlier_std_ratio: PositiveFloat = 2.5  # statistical outlier removal: std-dev multiplier


class SegmentationSettings(StrictModel):
    plane_distance_m: PositiveFloat = 0.006  # RANSAC inlier distance for the table plane
    plane_iterations: Annotated[int, Field(ge=10)] = 200
    plane_max_tilt_deg: PositiveFloat = 20.0  # the table plane's normal must be this close to base +z
    min_height_m: PositiveFloat = 0.008  # points lower than this above the plane belong to the table
    cluster_eps_m: PositiveFloat = 0.012  # DBSCAN neighbourhood radius
    cluster_min_points: Annotated[int, Field(ge=1)] = 8  # DBSCAN core-point neighbours
    min_cluster_points: Annotated[int, Field(ge=1)] = 30  # smaller clusters are noise
    max_cluster_extent_m: PositiveFloat = 0.35  # larger clusters are not objects (an arm, the table edge)
    top_band_m: PositiveFloat = 0.008  # points within this of the top height form the top face
    top_min_normal_z: Annotated[float, Field(ge=0, le=1)] = 0.8  # |normal . up| of a top-face point


class NoiseSettings(StrictModel):
    """Adapting to the depth noise measured in each frame (see ``noise_adapt.py`` and docs/perception.md)."""

    adapt: bool = True  # measure the noise and adapt; False keeps the fixed thresholds above
    tuned_sigma_m: PositiveFloat = 0.0025  # per-pixel depth error the fixed thresholds were tuned at (1x, ~1 m)
    window_efficiency: Annotated[float, Field(gt=0, le=1)] = 0.7  # share of a window's pixels the gate keeps
    max_filter_radius_px: Annotated[int, Field(ge=1, le=6)] = 4  # largest denoising window: (2r+1)^2 pixels
    gate_sigmas: PositiveFloat = 2.5  # neighbours further than this many sigma from the median are not averaged
    plane_sigmas: PositiveFloat = 3.0  # plane inlier distance >= this many height sigmas
    height_sigmas: PositiveFloat = 3.5  # an object point stands at least this many height sigmas above the plane
    top_band_sigmas: PositiveFloat = 3.0  # top-face band >= this many height sigmas
    cluster_spacings: PositiveFloat = 3.0  # DBSCAN radius >= this many median point spacings


class ColorSettings(StrictModel):
    """Colour names to HSV boxes; morphology and area limits for the colour masks."""

    ranges: dict[str, tuple[HsvRange, ...]] = Field(default_factory=lambda: dict(DEFAULT_COLORS))
    morph_kernel_px: Annotated[int, Field(ge=1, le=31)] = 3
    min_area_px: Annotated[int, Field(ge=1)] = 40
    min_match_fraction: Annotated[float, Field(ge=0, le=1)] = 0.3  # cluster pixels inside the mask


class GraspSettings(StrictModel):
    """Top-down parallel-jaw grasp synthesis; the gripper's numbers come from ``robot_description``."""

    max_opening_m: PositiveFloat = MAX_OPENING_M  # the gripper's full opening between the pads
    width_margin_m: NonNegFloat = 0.010  # required play between object and open pads (both sides together)
    tcp_to_fingertip_m: PositiveFloat = TCP_TO_FINGERTIP_M  # finger tips lie this far below the tcp
    fingertip_clearance_m: NonNegFloat = 0.005  # finger tips stay at least this far above the table
    palm_above_tcp_m: PositiveFloat = 0.040  # the palm's underside lies this far above the tcp
    palm_clearance_m: NonNegFloat = 0.005  # the palm stays this far above the object's top
    tall_top_offset_m: PositiveFloat = 0.020  # a tall object is grasped with the tcp this far below its top
    pregrasp_offset_m: PositiveFloat = 0.10  # the pre-grasp is this far above the grasp
    pad_thickness_m: PositiveFloat = 0.012  # finger pad size along the closing direction
    pad_depth_m: PositiveFloat = 0.020  # finger pad size across the closing direction
    min_clearance_m: NonNegFloat = 0.005  # open pads must stay this far from neighbouring objects
    round_step_deg: Annotated[float, Field(gt=0, le=90)] = 30.0  # closing directions tried on round objects
    weight_width: NonNegFloat = 0.4  # score weight of the width margin
    weight_alignment: NonNegFloat = 0.3  # score weight of closing across the narrow side
    weight_clearance: NonNegFloat = 0.3  # score weight of the distance to neighbours
    weight_forward: NonNegFloat = 0.02  # tie-break: tcp x pointing away from the robot base


class PerceptionConfig(StrictModel):
    roi: RegionOfInterest = RegionOfInterest()
    cloud: CloudSettings = CloudSettings()
    segmentation: SegmentationSettings = SegmentationSettings()
    noise: NoiseSettings = NoiseSettings()
    color: ColorSettings = ColorSettings()
    grasp: GraspSettings = GraspSettings()

    @classmethod
    def for_scene(cls, scene: Scene, margin_m: float = 0.02) -> PerceptionConfig:
        """Default settings with the region of interest taken from a scene's workspace."""
        return cls().with_scene(scene, margin_m)

    def with_scene(self, scene: Scene, margin_m: float = 0.02) -> PerceptionConfig:
        """This configuration with its region of interest set from a scene's workspace (world -> base)."""
        roi = roi_from_scene(scene, margin_m)
        return self.model_copy(update={"roi": roi})


def roi_from_scene(scene: Scene, margin_m: float = 0.02) -> RegionOfInterest:
    """The scene's workspace box (world frame) as an axis-aligned box in the base frame (a superset when the
    base is yawed), grown by ``margin_m`` sideways and reaching 3 cm below the table top."""
    ws = scene.workspace
    corners_world = np.array(
        [[x, y, z] for x in ws.x_m for y in ws.y_m for z in (-0.03, ws.z_max_m)], dtype=float
    )
    corners_base = transform_points(inv(scene.T_world_base()), corners_world)
    lo, hi = corners_base.min(axis=0), corners_base.max(axis=0)
    return RegionOfInterest(
        x_m=(float(lo[0] - margin_m), float(hi[0] + margin_m)),
        y_m=(float(lo[1] - margin_m), float(hi[1] + margin_m)),
        z_m=(float(lo[2]), float(hi[2])),
    )


def load_perception_config(path: str | Path) -> PerceptionConfig:
    """Read a perception settings file; raises ConfigError (file:line: problem)."""
    return load_model(PerceptionConfig, path)
