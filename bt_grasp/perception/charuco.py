"""The ChArUco calibration board: its description, its image, and its pose from a camera image.

Board frame (OpenCV's object points): origin at the outer corner of the first square, x along the
``squares_x`` side, y along the ``squares_y`` side (down the generated image), z = x cross y, pointing
*into* the board: a camera that sees the printed side looks along +z of the board.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import lru_cache
from typing import Annotated

import cv2
import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bt_grasp.files.config import StrictModel
from bt_grasp.geometry import Mat4, make_T
from bt_grasp.interfaces import CameraIntrinsics

log = logging.getLogger(__name__)


class BoardSpec(StrictModel):
    """A ChArUco board: squares (count, side), markers (side), ArUco dictionary; metres."""

    dictionary: str = "DICT_5X5_100"
    squares_x: Annotated[int, Field(ge=3, le=30)] = 5
    squares_y: Annotated[int, Field(ge=3, le=30)] = 7
    square_m: Annotated[float, Field(gt=0.001, le=0.5)] = 0.035
    marker_m: Annotated[float, Field(gt=0.001, le=0.5)] = 0.026

    @model_validator(mode="after")
    def _check(self) -> BoardSpec:
        if self.marker_m >= self.square_m:
            raise ValueError("marker_m must be smaller than square_m")
        if not self.dictionary.startswith("DICT_") or not hasattr(cv2.aruco, self.dictionary):
            raise ValueError(f"unknown ArUco dictionary '{self.dictionary}' (e.g. DICT_5X5_100)")
        markers = (self.squares_x * self.squares_y) // 2
        capacity = int(self.dictionary.rsplit("_", 1)[-1]) if self.dictionary.rsplit("_", 1)[-1].isdigit() else 0
        if capacity and markers > capacity:
            raise ValueError(f"the board needs {markers} markers but {self.dictionary} has {capacity}")
        return self

    @property
    def size_m(self) -> tuple[float, float]:
        return self.squares_x * self.square_m, self.squares_y * self.square_m

    @property
    def n_corners(self) -> int:
        return (self.squares_x - 1) * (self.squares_y - 1)


@lru_cache(maxsize=8)
def _board(spec: BoardSpec) -> cv2.aruco.CharucoBoard:
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, spec.dictionary))
    return cv2.aruco.CharucoBoard((spec.squares_x, spec.squares_y), spec.square_m, spec.marker_m, dictionary)


@lru_cache(maxsize=8)
def _detector(spec: BoardSpec) -> cv2.aruco.CharucoDetector:
    charuco_params = cv2.aruco.CharucoParameters()
    detector_params = cv2.aruco.DetectorParameters()
    detector_params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    return cv2.aruco.CharucoDetector(_board(spec), charuco_params, detector_params)


def board_image(spec: BoardSpec, px_per_square: int = 120, margin_px: int = 0) -> NDArray[np.uint8]:
    """The printable board, grey (H, W) uint8, exactly ``squares`` x ``px_per_square`` pixels (+ margins)."""
    w = spec.squares_x * px_per_square + 2 * margin_px
    h = spec.squares_y * px_per_square + 2 * margin_px
    return np.asarray(_board(spec).generateImage((w, h), marginSize=margin_px, borderBits=1), dtype=np.uint8)


def corner_object_points(spec: BoardSpec) -> NDArray[np.float64]:
    """The inner chessboard corners in the board frame (n, 3), indexed by ChArUco corner id."""
    return np.asarray(_board(spec).getChessboardCorners(), dtype=np.float64).reshape(-1, 3)


@dataclass(frozen=True)
class BoardObservation:
    """ChArUco corners seen in one image and the board pose from them (None when PnP was not possible)."""

    corner_ids: NDArray[np.int32]  # (n,)
    corners_px: NDArray[np.float64]  # (n, 2)
    T_camera_board: Mat4 | None
    reprojection_px: float  # RMS, inf when no pose

    @property
    def n_corners(self) -> int:
        return len(self.corner_ids)


def detect_board(
    color_rgb: NDArray[np.uint8], intrinsics: CameraIntrinsics, spec: BoardSpec, min_corners: int = 6
) -> BoardObservation:
    """Detect the ChArUco corners and solve the board pose (iterative PnP on the sub-pixel corners)."""
    grey = cv2.cvtColor(color_rgb, cv2.COLOR_RGB2GRAY)
    corners, ids, _marker_corners, _marker_ids = _detector(spec).detectBoard(grey)
    if ids is None or corners is None or len(ids) == 0:
        return BoardObservation(np.zeros(0, np.int32), np.zeros((0, 2)), None, float("inf"))
    ids = np.asarray(ids, dtype=np.int32).reshape(-1)
    px = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    if len(ids) < min_corners:
        return BoardObservation(ids, px, None, float("inf"))
    obj = corner_object_points(spec)[ids]
    K, dist = intrinsics.K, np.zeros(5)
    ok, rvec, tvec = cv2.solvePnP(obj, px, K, dist, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        return BoardObservation(ids, px, None, float("inf"))
    rvec, tvec = cv2.solvePnPRefineLM(obj, px, K, dist, rvec, tvec)
    projected, _ = cv2.projectPoints(obj, rvec, tvec, K, dist)
    rms = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - px) ** 2, axis=1))))
    R, _ = cv2.Rodrigues(rvec)
    return BoardObservation(ids, px, make_T(np.asarray(R, dtype=float), np.asarray(tvec, dtype=float).reshape(3)), rms)
