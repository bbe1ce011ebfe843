"""A calibration that reads as the loaded one plus an offset (the camera was bumped after calibrating)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import T_from_xyz_rpy


def offset_transform(dxyz_mm: tuple[float, float, float], drpy_deg: tuple[float, float, float]) -> NDArray[np.float64]:
    """The offset as a 4x4 transform (translation in metres)."""
    return T_from_xyz_rpy(np.asarray(dxyz_mm, dtype=float) * 1e-3, np.deg2rad(np.asarray(drpy_deg, dtype=float)))


def apply_offset(T_ref_camera: NDArray[np.float64], T_offset: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotate the camera about its own origin by the offset's rotation (axes of the reference frame),
    then translate it by the offset's translation (reference frame)."""
    T = np.asarray(T_ref_camera, dtype=float).copy()
    T[:3, :3] = T_offset[:3, :3] @ T[:3, :3]
    T[:3, 3] = T[:3, 3] + T_offset[:3, 3]
    return T


class OffsetCalibration:
    """Reads like the wrapped calibration, except its camera pose carries the offset.

    Eye-to-hand: ``T_base_camera`` is offset in the base frame. Eye-in-hand: ``T_tool_camera`` is offset
    in the tool frame. Everything else (mount, tool_link, residuals, ...) is the real calibration's.
    """

    def __init__(self, inner: Any, T_offset: NDArray[np.float64]) -> None:
        self.inner = inner
        self.T_offset = np.asarray(T_offset, dtype=float)

    def __getattr__(self, name: str) -> Any:
        value = getattr(self.inner, name)
        mount = getattr(self.inner, "mount", "eye-to-hand")
        if (name == "T_base_camera" and mount == "eye-to-hand") or (
            name == "T_tool_camera" and mount == "eye-in-hand"
        ):
            return apply_offset(np.asarray(value, dtype=float), self.T_offset)
        return value
