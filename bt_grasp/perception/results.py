"""Typed results of perception and grasp synthesis (frozen dataclasses; statuses are enums, not strings)."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4


class PerceptionStatus(enum.Enum):
    OK = "ok"
    NO_DEPTH = "no_depth"  # no frame, or a depth image with no valid reading at all
    NO_POINTS = "no_points"  # valid depth, but nothing inside the region of interest (or no table plane)
    NO_OBJECTS = "no_objects"  # the table was found but nothing stands on it
    NO_MATCH = "no_match"  # objects were found, none matches the requested colour


@dataclass(frozen=True)
class Detection:
    """One object on the table, in the robot BASE frame.

    ``size_m`` is (length, width, height): length along the long axis of the footprint, whose direction in
    the table plane is ``yaw_rad`` (about base +z, in (-pi/2, pi/2]); height above the table plane.
    ``centroid_base_m`` is the centre of the object's bounding box (half the height above the table).
    ``pixel_box`` is (u_min, v_min, u_max, v_max) in the colour image.
    """

    label: str  # a colour name when the colour matched, else "object"
    pixel_box: tuple[int, int, int, int]
    centroid_base_m: tuple[float, float, float]
    size_m: tuple[float, float, float]
    yaw_rad: float
    point_count: int
    confidence: float  # 0..1
    color_fraction: float = 0.0  # fraction of the object's pixels inside the requested colour's mask
    principal_axes_base: tuple[tuple[float, float, float], ...] = ()  # PCA axes (unit vectors), largest first
    footprint_base_m: tuple[tuple[float, float], ...] = ()  # the footprint rectangle's 4 corners (x, y)
    shape: str = "box"  # "box" (a footprint with corners) or "round" (no preferred yaw: cylinder, sphere)

    @property
    def centroid(self) -> NDArray[np.float64]:
        return np.array(self.centroid_base_m, dtype=float)

    @property
    def table_z_m(self) -> float:
        """Height of the supporting table plane under the object (base frame z)."""
        return float(self.centroid_base_m[2] - self.size_m[2] / 2)


@dataclass(frozen=True)
class NoiseEstimate:
    """What the frame says about its depth noise, and what perception did about it."""

    k_per_m: float  # sigma(z) = k * z^2, metres of error per metre^2 of distance (1/m)
    working_depth_m: float  # median valid depth in the region of interest
    sigma_m: float  # k * working_depth^2: the per-pixel error where the objects are
    filter_radius_px: int  # 0: no denoising was needed
    sigma_after_m: float  # expected per-pixel error after the denoising

    def as_dict(self) -> dict[str, float]:
        return {"k_per_m": self.k_per_m, "working_depth_m": self.working_depth_m, "sigma_m": self.sigma_m,
                "filter_radius_px": float(self.filter_radius_px), "sigma_after_m": self.sigma_after_m}


@dataclass(frozen=True)
class PerceptionResult:
    """What one frame showed. ``detections`` are ranked: the best match for the request first."""

    status: PerceptionStatus
    detections: tuple[Detection, ...] = ()
    timings_ms: dict[str, float] = field(default_factory=dict)
    message: str = ""
    table_plane_base: tuple[float, float, float, float] | None = None  # a, b, c, d with ax+by+cz+d=0, c>0
    others: tuple[Detection, ...] = ()  # every object cluster found (for clearance checks)
    noise: NoiseEstimate | None = None  # the depth noise measured in the frame and what was done about it
    height_sigma_m: float = 0.0  # spread of the table points about the fitted plane (after denoising)

    @property
    def ok(self) -> bool:
        return self.status is PerceptionStatus.OK

    @property
    def best(self) -> Detection | None:
        return self.detections[0] if self.detections else None


class GraspStatus(enum.Enum):
    OK = "ok"
    TOO_WIDE = "too_wide"  # no side of the object fits between the open fingers with the margin
    NO_CLEARANCE = "no_clearance"  # every fitting grasp would put a finger into a neighbour


@dataclass(frozen=True)
class GraspCandidate:
    """A top-down parallel-jaw grasp in the BASE frame; tcp z points down, tcp y is the closing direction."""

    T_base_tcp_grasp: Mat4
    T_base_tcp_pregrasp: Mat4
    width_m: float  # the object's width between the pads (what the fingers will close on)
    score: float  # higher is better; see grasps.score_terms
    reason: str  # how the score came about, for logs


@dataclass(frozen=True)
class GraspResult:
    status: GraspStatus
    candidates: tuple[GraspCandidate, ...] = ()
    message: str = ""

    @property
    def ok(self) -> bool:
        return self.status is GraspStatus.OK

    @property
    def best(self) -> GraspCandidate | None:
        return self.candidates[0] if self.candidates else None
