"""Boxes seen by the camera: a box's corners projected into the image (pinhole, OpenCV convention)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

_SIGNS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
#: corner index pairs of a box's 12 edges (corners ordered as ``_SIGNS``)
BOX_EDGES = ((0, 1), (1, 3), (3, 2), (2, 0), (4, 5), (5, 7), (7, 6), (6, 4), (0, 4), (1, 5), (2, 6), (3, 7))


def box_corners_px(T_camera_base: ArrayLike, K: ArrayLike, T_base_box: ArrayLike,
                   size_m: tuple[float, float, float]) -> NDArray[np.float64] | None:
    """(8, 2) pixel coordinates of the box's corners, or None when a corner is not in front of the camera."""
    T_cb, T_bb = np.asarray(T_camera_base, dtype=np.float64), np.asarray(T_base_box, dtype=np.float64)
    corners = (T_bb[:3, :3] @ (_SIGNS * np.asarray(size_m, dtype=np.float64)).T).T + T_bb[:3, 3]
    cam = (T_cb[:3, :3] @ corners.T).T + T_cb[:3, 3]
    if np.any(cam[:, 2] <= 0.01):
        return None
    uv = (np.asarray(K, dtype=np.float64) @ cam.T).T
    px: NDArray[np.float64] = uv[:, :2] / uv[:, 2:3]
    return px
