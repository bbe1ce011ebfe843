"""Rigid transforms as 4x4 numpy arrays named ``T_a_b`` (maps points in frame b to frame a).

Quaternions are (w, x, y, z) unless a name says ``xyzw``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Mat4 = NDArray[np.float64]


def make_T(
    rotation: NDArray[np.float64] | None = None, translation: NDArray[np.float64] | list[float] | None = None
) -> Mat4:
    """A homogeneous transform from a 3x3 rotation and a translation in metres."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    if translation is not None:
        T[:3, 3] = np.asarray(translation, dtype=float)
    return T


def T_from_xyz_rpy(xyz: list[float] | NDArray[np.float64], rpy_rad: list[float] | NDArray[np.float64]) -> Mat4:
    """Transform from a translation (m) and URDF-style roll-pitch-yaw (rad, fixed axes x, y, z)."""
    from scipy.spatial.transform import Rotation  # on first use: scipy.spatial costs ~0.3 s to import

    return make_T(Rotation.from_euler("xyz", rpy_rad).as_matrix(), xyz)


def T_from_pos_quat_wxyz(pos: NDArray[np.float64] | list[float], quat_wxyz: NDArray[np.float64] | list[float]) -> Mat4:
    w, x, y, z = (float(v) for v in quat_wxyz)
    from scipy.spatial.transform import Rotation

    return make_T(Rotation.from_quat([x, y, z, w]).as_matrix(), pos)


def quat_wxyz(T: Mat4) -> NDArray[np.float64]:
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    return np.array([w, x, y, z])


def inv(T: Mat4) -> Mat4:
    """Inverse of a rigid transform."""
    Ti = np.eye(4)
    R = T[:3, :3]
    Ti[:3, :3] = R.T
    Ti[:3, 3] = -R.T @ T[:3, 3]
    return Ti


def rotation_angle_rad(R_a: NDArray[np.float64], R_b: NDArray[np.float64]) -> float:
    """Angle of the rotation that takes R_a to R_b, in radians."""
    c = (np.trace(R_a.T @ R_b) - 1.0) / 2.0
    return float(np.arccos(np.clip(c, -1.0, 1.0)))


def pose_error(T_a: Mat4, T_b: Mat4) -> tuple[float, float]:
    """(translation error in metres, rotation error in radians) between two poses."""
    return float(np.linalg.norm(T_a[:3, 3] - T_b[:3, 3])), rotation_angle_rad(T_a[:3, :3], T_b[:3, :3])


def transform_points(T_a_b: Mat4, points_b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Map an (N, 3) array of points from frame b to frame a."""
    return points_b @ T_a_b[:3, :3].T + T_a_b[:3, 3]


def rot_z(angle_rad: float) -> NDArray[np.float64]:
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def convex_hull_xy(points: NDArray[np.float64], decimals: int = 9) -> NDArray[np.float64]:
    """The 2-D convex hull of points (N, 2), counter-clockwise (Andrew's monotone chain); points equal to
    ``decimals`` places are one point; fewer than three distinct points are returned as they are."""
    pts = sorted({(round(float(x), decimals), round(float(y), decimals)) for x, y in points})
    if len(pts) < 3:
        return np.array(pts, dtype=float)

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def signed_mm(value_m: float, positive: str, negative: str, decimals: int = 0) -> str:
    """A signed distance in words, rounded to ``decimals`` of a millimetre: ``"3 mm above"``, ``"2 mm below"``,
    ``"0 mm above"`` (never ``"-0 mm"``, never a sign the reader must decode)."""
    mm = round(float(value_m) * 1000.0, decimals)
    return f"{abs(mm):.{decimals}f} mm {negative if mm < 0 else positive}"
