"""Hand-eye solving on synthetic, exactly consistent samples: every method recovers X, for both mounts."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bt_grasp.geometry import inv, make_T, pose_error
from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.perception.charuco import BoardSpec, corner_object_points
from bt_grasp.perception.handeye import View, predicted_T_camera_board, solve_hand_eye

INTR = CameraIntrinsics(640, 480, 600.0, 600.0, 319.5, 239.5)


def _project(T, pts):
    p = pts @ T[:3, :3].T + T[:3, 3]
    return np.stack([600 * p[:, 0] / p[:, 2] + 319.5, 600 * p[:, 1] / p[:, 2] + 239.5], axis=1)


def _views(mount: str, X, Y, n: int, px_noise: float, seed: int = 1) -> list[View]:
    rng = np.random.default_rng(seed)
    obj = corner_object_points(BoardSpec())
    views = []
    while len(views) < n:
        R = Rotation.from_rotvec(rng.normal(0, 0.35, 3)).as_matrix()
        if mount == "eye-to-hand":  # tool moves around in front of the camera
            T_base_tool = make_T(R @ np.diag([1.0, -1.0, -1.0]), np.array([0.5, 0, 0.4]) + rng.normal(0, 0.06, 3))
        else:  # camera looks down at the board from above
            T_base_tool = make_T(R @ np.diag([1.0, -1.0, -1.0]), np.array([0.4, 0.3, 0.45]) + rng.normal(0, 0.05, 3))
        T_cb = predicted_T_camera_board(mount, X, Y, T_base_tool)
        px = _project(T_cb, obj)
        if T_cb[2, 3] < 0.2 or np.any((px < 0) | (px > [639, 479])):
            continue
        px = px + rng.normal(0, px_noise, px.shape)
        views.append(View(T_base_tool, T_cb, np.arange(len(obj), dtype=np.int32), px, obj))
    return views


@pytest.mark.parametrize("mount", ["eye-to-hand", "eye-in-hand"])
def test_every_method_recovers_the_transform(mount: str) -> None:
    if mount == "eye-to-hand":
        X = make_T(Rotation.from_euler("xyz", [-130, 0, 90], degrees=True).as_matrix(), [1.0, 0.05, 0.7])
        Y = make_T(np.diag([1.0, -1.0, -1.0]), [-0.0875, 0.1225, 0.11])
    else:
        X = make_T(Rotation.from_euler("xyz", [2, 12, 1], degrees=True).as_matrix(), [-0.07, 0.0, 0.01])
        Y = make_T(np.diag([1.0, -1.0, -1.0]), [0.3, 0.4, 0.0005])
    solution = solve_hand_eye(mount, _views(mount, X, Y, 12, 0.0), INTR, corner_object_points(BoardSpec()))
    assert {"tsai", "park", "horaud", "andreff", "daniilidis", "robot_world_shah", "robot_world_li"} <= set(
        solution.per_method
    )
    for name, result in solution.per_method.items():
        dt, dr = pose_error(result.X, X)
        assert dt < 1e-5 and dr < 1e-5, name
        assert result.reprojection_px < 1e-3
    assert pose_error(inv(solution.Y), inv(Y))[0] < 1e-5


def test_refinement_keeps_the_noisy_result_accurate() -> None:
    X = make_T(Rotation.from_euler("xyz", [-130, 0, 90], degrees=True).as_matrix(), [1.0, 0.05, 0.7])
    Y = make_T(np.diag([1.0, -1.0, -1.0]), [-0.0875, 0.1225, 0.11])
    views = _views("eye-to-hand", X, Y, 15, 0.15, seed=3)
    solution = solve_hand_eye("eye-to-hand", views, INTR, corner_object_points(BoardSpec()))
    dt, dr = pose_error(solution.X, X)
    assert dt < 1e-3 and np.degrees(dr) < 0.05
    assert solution.chosen.reprojection_px < 0.25
