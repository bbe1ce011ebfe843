"""A calibration that reads as the loaded one plus an offset (the camera was bumped after calibrating)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.services import CameraCalibration
from bt_grasp.geometry import Mat4, T_from_xyz_rpy
from bt_grasp.interfaces import Mount


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
    """Reads like the wrapped calibration (a :class:`bt_grasp.behaviours.services.CameraCalibration`),
    except that its camera pose carries the offset: in the base frame for an eye-to-hand camera, in the
    tool frame for an eye-in-hand one (where the pose is ``T_base_tool @ T_tool_camera``)."""

    def __init__(self, inner: CameraCalibration, T_offset: NDArray[np.float64]) -> None:
        self.inner = inner
        self.T_offset = np.asarray(T_offset, dtype=float)

    @property
    def mount(self) -> str:
        return self.inner.mount

    @property
    def tool_link(self) -> str:
        return self.inner.tool_link

    def T_base_camera_at(self, T_base_tool: Mat4 | None = None) -> Mat4:
        T = np.asarray(self.inner.T_base_camera_at(T_base_tool), dtype=float)
        if self.mount == Mount.EYE_IN_HAND and T_base_tool is not None:
            T_tool = np.asarray(T_base_tool, dtype=float)
            return T_tool @ apply_offset(np.linalg.inv(T_tool) @ T, self.T_offset)
        return apply_offset(T, self.T_offset)
