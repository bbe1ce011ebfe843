"""Hand-eye solving: OpenCV's five AX = XB methods and two robot-world methods, scored by consistency.

Unknowns (both 4x4, ``T_a_b`` maps b to a):

* eye-to-hand (camera fixed, board on the tool): ``X = T_base_camera``, ``Y = T_tool_board``;
  ``T_camera_board_i = inv(X) @ T_base_tool_i @ Y``.
* eye-in-hand (camera on the tool, board fixed): ``X = T_tool_camera``, ``Y = T_base_board``;
  ``T_camera_board_i = inv(X) @ inv(T_base_tool_i) @ Y``.

``cv2.calibrateHandEye`` solves the eye-in-hand form from (gripper2base = ``T_base_tool``, target2cam =
``T_camera_board``) and returns cam2gripper = ``T_tool_camera``; for eye-to-hand the same call with the
inverted tool poses (base2gripper) returns ``T_base_camera``. ``cv2.calibrateRobotWorldHandEye`` solves
``T_c_w = T_c_g T_g_b T_b_w`` for both unknowns at once; eye-to-hand maps onto it with the board as its
"camera" and the camera as its "world".

No method is chosen by ground truth: each result implies a board pose per view (``Y_i``); the chosen one
is the method whose implied board poses agree best (the RMS scatter, in mm, of the board's corners
transformed by every ``Y_i``). The chosen result is then refined by Levenberg-Marquardt on the corner
reprojection error of all views together (``X`` and ``Y`` jointly), and kept if it reprojects better.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from bt_grasp.geometry import Mat4, inv, make_T, rotation_angle_rad, transform_points
from bt_grasp.interfaces import CameraIntrinsics, Mount

log = logging.getLogger(__name__)

EYE_TO_HAND = Mount.EYE_TO_HAND
EYE_IN_HAND = Mount.EYE_IN_HAND
MOUNTS = (EYE_TO_HAND, EYE_IN_HAND)

HAND_EYE_METHODS: dict[str, int] = {
    "tsai": cv2.CALIB_HAND_EYE_TSAI,
    "park": cv2.CALIB_HAND_EYE_PARK,
    "horaud": cv2.CALIB_HAND_EYE_HORAUD,
    "andreff": cv2.CALIB_HAND_EYE_ANDREFF,
    "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS,
}
ROBOT_WORLD_METHODS: dict[str, int] = {
    "shah": cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH,
    "li": cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI,
}


@dataclass(frozen=True)
class View:
    """One accepted calibration sample: the tool pose at capture and what the camera saw of the board."""

    T_base_tool: Mat4
    T_camera_board: Mat4
    corner_ids: NDArray[np.int32]
    corners_px: NDArray[np.float64]
    object_points: NDArray[np.float64]  # (n, 3) board-frame points of corner_ids


@dataclass(frozen=True)
class MethodResult:
    method: str
    X: Mat4  # T_base_camera (eye-to-hand) or T_tool_camera (eye-in-hand)
    Y: Mat4  # T_tool_board (eye-to-hand) or T_base_board (eye-in-hand): mean of the implied poses
    residual_mm: float  # RMS distance of the implied board origins from their mean
    residual_deg: float  # RMS angle of the implied board orientations from their mean
    scatter_mm: float  # RMS scatter of the board's corners under the implied poses (the selection score)
    reprojection_px: float  # RMS corner reprojection error of (X, Y) over all views

    def as_dict(self) -> dict[str, float]:
        return {
            "residual_mm": round(self.residual_mm, 4),
            "residual_deg": round(self.residual_deg, 5),
            "scatter_mm": round(self.scatter_mm, 4),
            "reprojection_px": round(self.reprojection_px, 4),
        }


def _Rt(Ts: Sequence[Mat4]) -> tuple[list[NDArray[np.float64]], list[NDArray[np.float64]]]:
    return [np.ascontiguousarray(T[:3, :3]) for T in Ts], [np.ascontiguousarray(T[:3, 3:4]) for T in Ts]


def implied_Y(mount: str, X: Mat4, view: View) -> Mat4:
    if mount == EYE_TO_HAND:
        return inv(view.T_base_tool) @ X @ view.T_camera_board
    return view.T_base_tool @ X @ view.T_camera_board


def predicted_T_camera_board(mount: str, X: Mat4, Y: Mat4, T_base_tool: Mat4) -> Mat4:
    if mount == EYE_TO_HAND:
        return inv(X) @ T_base_tool @ Y
    return inv(X) @ inv(T_base_tool) @ Y


def mean_pose(Ts: Sequence[Mat4]) -> Mat4:
    """Chordal mean of the rotations (projected back onto SO(3)) and mean of the translations."""
    M = np.sum([T[:3, :3] for T in Ts], axis=0)
    U, _, Vt = np.linalg.svd(M)
    R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    return make_T(R, np.mean([T[:3, 3] for T in Ts], axis=0))


def _project(T_camera_board: Mat4, points: NDArray[np.float64], K: NDArray[np.float64]) -> NDArray[np.float64]:
    p = transform_points(T_camera_board, points)
    return np.stack([K[0, 0] * p[:, 0] / p[:, 2] + K[0, 2], K[1, 1] * p[:, 1] / p[:, 2] + K[1, 2]], axis=1)


def _reprojection_residuals(mount: str, X: Mat4, Y: Mat4, views: Sequence[View],
                            K: NDArray[np.float64]) -> NDArray[np.float64]:
    out = [
        (_project(predicted_T_camera_board(mount, X, Y, v.T_base_tool), v.object_points, K) - v.corners_px).ravel()
        for v in views
    ]
    return np.concatenate(out)


def score(method: str, mount: str, X: Mat4, views: Sequence[View], board_corners: NDArray[np.float64],
          K: NDArray[np.float64], Y: Mat4 | None = None) -> MethodResult:
    Ys = [implied_Y(mount, X, v) for v in views]
    Y_mean = mean_pose(Ys) if Y is None else Y
    d_t = [np.linalg.norm(T[:3, 3] - Y_mean[:3, 3]) for T in Ys]
    d_r = [rotation_angle_rad(T[:3, :3], Y_mean[:3, :3]) for T in Ys]
    corners = [transform_points(T, board_corners) for T in Ys]
    centre = np.mean(corners, axis=0)
    scatter = float(np.sqrt(np.mean([np.sum((c - centre) ** 2, axis=1) for c in corners])))
    reproj = _reprojection_residuals(mount, X, Y_mean, views, K).reshape(-1, 2)
    return MethodResult(
        method=method,
        X=X,
        Y=Y_mean,
        residual_mm=float(np.sqrt(np.mean(np.square(d_t)))) * 1e3,
        residual_deg=float(np.degrees(np.sqrt(np.mean(np.square(d_r))))),
        scatter_mm=scatter * 1e3,
        reprojection_px=float(np.sqrt(np.mean(np.sum(reproj**2, axis=1)))),
    )


def solve_all(mount: str, views: Sequence[View]) -> dict[str, Mat4]:
    """X from every OpenCV method that returns a finite rigid transform."""
    if mount not in MOUNTS:
        raise ValueError(f"unknown mount {mount!r}; expected one of {MOUNTS}")
    tool = [v.T_base_tool for v in views]
    cam_board = [v.T_camera_board for v in views]
    out: dict[str, Mat4] = {}
    R_g, t_g = _Rt(tool if mount == EYE_IN_HAND else [inv(T) for T in tool])
    R_t, t_t = _Rt(cam_board)
    for name, flag in HAND_EYE_METHODS.items():
        try:
            R, t = cv2.calibrateHandEye(R_g, t_g, R_t, t_t, method=flag)
        except cv2.error as exc:
            log.warning("hand-eye method %s failed: %s", name, exc)
            continue
        X = make_T(np.asarray(R, dtype=float), np.asarray(t, dtype=float).reshape(3))
        if np.all(np.isfinite(X)):
            out[name] = X
    if mount == EYE_IN_HAND:
        R_w, t_w = _Rt(cam_board)
    else:
        R_w, t_w = _Rt([inv(T) for T in cam_board])
    R_b, t_b = _Rt([inv(T) for T in tool])
    for name, flag in ROBOT_WORLD_METHODS.items():
        try:
            R_bw, t_bw, R_gc, t_gc = cv2.calibrateRobotWorldHandEye(R_w, t_w, R_b, t_b, method=flag)
        except cv2.error as exc:
            log.warning("robot-world hand-eye method %s failed: %s", name, exc)
            continue
        T_wb = make_T(np.asarray(R_bw, dtype=float), np.asarray(t_bw, dtype=float).reshape(3))
        T_gc = make_T(np.asarray(R_gc, dtype=float), np.asarray(t_gc, dtype=float).reshape(3))
        # T_wb maps base points into the "world" frame, T_gc "gripper" points into the "camera" frame
        X = inv(T_wb) if mount == EYE_TO_HAND else inv(T_gc)
        if np.all(np.isfinite(X)):
            out[f"robot_world_{name}"] = X
    return out


def _to_vec(T: Mat4) -> NDArray[np.float64]:
    return np.concatenate([Rotation.from_matrix(T[:3, :3]).as_rotvec(), T[:3, 3]])


def _from_vec(v: NDArray[np.float64]) -> Mat4:
    return make_T(Rotation.from_rotvec(v[:3]).as_matrix(), v[3:6])


def refine(mount: str, X: Mat4, Y: Mat4, views: Sequence[View], K: NDArray[np.float64]) -> tuple[Mat4, Mat4]:
    """Joint Levenberg-Marquardt refinement of X and Y on the corner reprojection error."""

    def residuals(params: NDArray[np.float64]) -> NDArray[np.float64]:
        return _reprojection_residuals(mount, _from_vec(params[:6]), _from_vec(params[6:]), views, K)

    solution = least_squares(residuals, np.concatenate([_to_vec(X), _to_vec(Y)]), method="lm", x_scale="jac")
    return _from_vec(solution.x[:6]), _from_vec(solution.x[6:])


@dataclass(frozen=True)
class HandEyeSolution:
    mount: str
    method: str
    X: Mat4
    Y: Mat4
    per_method: dict[str, MethodResult]

    @property
    def chosen(self) -> MethodResult:
        return self.per_method[self.method]


def solve_hand_eye(mount: str, views: Sequence[View], intrinsics: CameraIntrinsics,
                   board_corners: NDArray[np.float64], *, refine_result: bool = True) -> HandEyeSolution:
    """Run every method, score each by consistency, refine the most consistent one; needs >= 3 views."""
    if len(views) < 3:
        raise ValueError(f"hand-eye calibration needs at least 3 views, got {len(views)}")
    K = intrinsics.K
    results = {name: score(name, mount, X, views, board_corners, K) for name, X in solve_all(mount, views).items()}
    if not results:
        raise ValueError("no hand-eye method produced a finite result")
    best = min(results.values(), key=lambda r: r.scatter_mm)
    chosen = best.method
    if refine_result:
        X, Y = refine(mount, best.X, best.Y, views, K)
        refined = score(f"{best.method}+lm", mount, X, views, board_corners, K, Y=Y)
        results[refined.method] = refined
        if refined.reprojection_px < best.reprojection_px:
            chosen = refined.method
    for r in results.values():
        log.info("hand-eye %-20s scatter %.3f mm, residual %.3f mm / %.4f deg, reprojection %.3f px",
                 r.method, r.scatter_mm, r.residual_mm, r.residual_deg, r.reprojection_px)
    picked = results[chosen]
    return HandEyeSolution(mount, chosen, picked.X, picked.Y, results)
