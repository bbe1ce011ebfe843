"""A calibration that reads as the loaded one plus an offset (the camera was bumped after calibrating)."""

from __future__ import annotations

from collections.abc import Callable
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

    Eye-to-hand: ``T_base_camera`` (an attribute or a method) is offset in the base frame. Eye-in-hand:
    ``T_tool_camera``, or the result of the method ``T_base_camera(T_base_tool)``, is offset in the tool
    frame. Everything else (mount, tool_link, residuals, ...) is the real calibration's.
    """

    def __init__(self, inner: Any, T_offset: NDArray[np.float64]) -> None:
        self.inner = inner
        self.T_offset = np.asarray(T_offset, dtype=float)

    def __getattr__(self, name: str) -> Any:
        value = getattr(self.inner, name)
        mount = getattr(self.inner, "mount", "eye-to-hand")
        if name == "T_tool_camera" and mount == "eye-in-hand" and not callable(value):
            return apply_offset(np.asarray(value, dtype=float), self.T_offset)
        if name != "T_base_camera":
            return value
        if not callable(value):
            return apply_offset(np.asarray(value, dtype=float), self.T_offset) if mount == "eye-to-hand" else value
        return self._offset_method(value, mount)

    def _offset_method(self, method: Callable[..., Any], mount: str) -> Callable[..., NDArray[np.float64]]:
        """``T_base_camera(T_base_tool=None)`` as a method: offset its result (in the tool frame for
        eye-in-hand, where the result is T_base_tool @ T_tool_camera)."""

        def T_base_camera(T_base_tool: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
            T = np.asarray(method(T_base_tool) if T_base_tool is not None else method(), dtype=float)
            if mount == "eye-in-hand" and T_base_tool is not None:
                T_tool = np.asarray(T_base_tool, dtype=float)
                return T_tool @ apply_offset(np.linalg.inv(T_tool) @ T, self.T_offset)
            return apply_offset(T, self.T_offset)

        return T_base_camera
