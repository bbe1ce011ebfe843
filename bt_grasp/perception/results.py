"""Typed results of perception and grasp synthesis (frozen dataclasses; statuses are enums, not strings)."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4


class ShapeClass(enum.Enum):
    """What an object's visible geometry looks like (from its boxes and top view; never from its colour)."""

    BOX_LIKE = "box-like"  # a flat top filling a rectangular footprint
    CYLINDER_LIKE = "cylinder-like"  # a round footprint (standing can, bottle, bowl), or a lying curved-top one
    ELONGATED = "elongated"  # one side at least 2.5 times the next (a rod, a pen, a banana, a tall narrow object)
    FLAT = "flat"  # much lower than wide (a plate, a thin part)
    OTHER = "other"  # none of these (a mug with its handle, an L bracket, a T tool, a ring)


Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class OrientedBox:
    """A box in the robot BASE frame: ``axes`` are its unit x, y, z axes (the rotation's columns, a
    right-handed frame), ``extents_m`` its full side lengths along them, ``center_m`` its centre."""

    center_m: Vec3
    axes: tuple[Vec3, Vec3, Vec3]
    extents_m: Vec3

    @property
    def rotation(self) -> NDArray[np.float64]:
        """3x3 rotation base <- box (columns are the axes)."""
        return np.array(self.axes, dtype=float).T

    @property
    def T_base_box(self) -> Mat4:
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.center_m
        return T

    def corners(self) -> NDArray[np.float64]:
        """The 8 corners (8, 3), base frame."""
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        return np.asarray(np.asarray(self.center_m) + (signs * np.asarray(self.extents_m) / 2) @ self.rotation.T,
                          dtype=np.float64)


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

    Objects are found by geometry alone (the table plane and clusters above it); colour is an attribute:
    ``label`` is the colour name when most of the object's pixels match one (else "object", as before),
    ``color_name``/``color_rgb`` are always the dominant colour (nearest named colour, median RGB).
    ``obb`` is the gravity-aligned box (z = the table normal, x = the footprint's long side, extents =
    ``size_m``, centre = ``centroid_base_m``); ``obb_pca`` is the box in the full PCA frame of the visible
    points (x = ``principal_axis_base``, extents between robust quantiles). ``points_base_m`` are the
    visible points (N, 3), base frame, read-only; ``cluster_note`` says why a cluster may hold more than one
    object (empty when nothing suggests it) and ``split_from`` how many clusters it was cut from (0: not cut).
    ``class_name``/``class_score``: the class and score of the learned detector's box joined with this object
    (``bt_grasp.perception.learned``); "" and 0 when the geometric detector found it or no box covered it.
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
    # added with issue 28 (geometry first, colour as an attribute); defaults keep hand-made detections valid
    obb: OrientedBox | None = None  # gravity-aligned oriented box
    obb_pca: OrientedBox | None = None  # oriented box in the PCA frame of the visible points
    principal_axis_base: Vec3 = (0.0, 0.0, 0.0)  # unit vector of largest spread (sign: +x, else +y, else +z)
    extents_m: Vec3 = (0.0, 0.0, 0.0)  # obb_pca's extents: along the principal axis, the second, the third
    points_base_m: NDArray[np.float64] | None = field(default=None, compare=False, repr=False)
    color_name: str = ""  # the dominant colour's name (nearest named colour; "" when unknown)
    color_rgb: tuple[int, int, int] = (0, 0, 0)  # the median colour of the object's pixels
    shape_class: ShapeClass = ShapeClass.OTHER
    cluster_note: str = ""  # e.g. why this cluster may be several touching objects
    split_from: int = 0  # >0: this detection was cut out of one cluster holding that many objects
    # added with issue 23 (the learned detector): the class its oriented box named, "" when no box named it
    class_name: str = ""
    class_score: float = 0.0  # the box's class score (sigmoid), 0..1; 0 when no box named it

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
