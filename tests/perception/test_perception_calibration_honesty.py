"""Calibration reads only images and forward kinematics: the nominal camera pose from the scene file only
chooses where to look. Planned from a nominal pose 4 cm off, it still recovers the TRUE camera pose."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.behaviours.calibration_job import CalibrationJob
from bt_grasp.behaviours.cell import make_cell
from bt_grasp.episode.calibration import tick_calibration
from bt_grasp.geometry import pose_error
from bt_grasp.scene.format import load_scene
from bt_grasp.sim.charuco import mount_calibration_board
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World

pytestmark = pytest.mark.sim

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "tabletop.yaml"


def test_eye_to_hand_result_does_not_follow_a_wrong_nominal_camera_pose() -> None:
    scene = load_scene(SCENE)
    world = World(scene, seed=4, camera_mount="eye-to-hand")
    board = mount_calibration_board(world)
    # the installation drawing is wrong by (3, -2, 2) cm: the planner looks from the wrong place
    e2h = scene.camera.eye_to_hand
    wrong_position = tuple(float(p + d) for p, d in zip(e2h.position_m, (0.03, -0.02, 0.02), strict=True))
    wrong = scene.model_copy(
        update={
            "camera": scene.camera.model_copy(
                update={"eye_to_hand": e2h.model_copy(update={"position_m": wrong_position})}
            )
        }
    )
    # the cell (what the robot knows) has the wrong drawing; the simulated world has the true camera
    cell = make_cell(world.robot, world.camera, world.clock, wrong, 4, board=board)
    job = CalibrationJob(cell, 15)
    run, _ = tick_calibration(world, job)
    T_true = GroundTruthOracle(world).T_base_camera_cv()
    err_true_m, err_true_rad = pose_error(run.solution.X, T_true)
    err_nominal_m, _ = pose_error(run.solution.X, job.collector.plan.T_nominal_camera)
    assert err_true_m < 1e-3 and np.degrees(err_true_rad) < 0.1, (err_true_m, np.degrees(err_true_rad))
    assert err_nominal_m > 0.03, "the result must not be the nominal pose the planner was given"
