"""The simulated cell: rendering, depth geometry, determinism, and grasping by friction only."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.scene.format import load_scene
from bt_grasp.sim.noise import depth_rms_m
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.world import World

pytestmark = pytest.mark.sim


@pytest.fixture(scope="module")
def world(tabletop_scene_path: Path) -> World:
    return World.from_file(tabletop_scene_path, seed=0)


def _table_depth(world: World, T_world_cv: np.ndarray) -> np.ndarray:
    """Depth of the table plane z=0 along every pixel ray, from the scene geometry."""
    K = world.camera.intrinsics
    u, v = np.meshgrid(np.arange(K.width_px), np.arange(K.height_px))
    rays = np.stack([(u - K.cx_px) / K.fx_px, (v - K.cy_px) / K.fy_px, np.ones_like(u, dtype=float)], -1)
    rays_world_z = rays @ T_world_cv[2, :3]
    return -T_world_cv[2, 3] / rays_world_z


def test_table_depth_matches_geometry(world: World) -> None:
    oracle = GroundTruthOracle(world)
    color, depth_true = world.camera.render_true()
    predicted = _table_depth(world, oracle.T_world_camera_cv())
    # table pixels: the rendered depth agrees with the plane (objects and the robot are nearer)
    table = (np.abs(depth_true - predicted) < 0.01) & (depth_true > 0)
    assert table.mean() > 0.5, "most of the image is table"
    assert np.median(np.abs(depth_true[table] - predicted[table])) < 2e-4
    frame = world.camera.capture()
    assert frame is not None
    noisy = frame.depth_m
    ok = table & (noisy > 0)
    err = noisy[ok] - predicted[ok]
    sigma = depth_rms_m(predicted[ok], world.config.camera.noise)
    # within the noise model: unbiased, spread close to the model's RMS plus quantisation
    assert abs(float(np.mean(err))) < 1e-3
    assert np.std(err) < 1.5 * float(np.sqrt(np.mean(sigma**2)) + 0.001)
    assert color.shape == (480, 640, 3) and frame.depth_m.dtype == np.float32


def test_same_seed_same_scene_and_images(tabletop_scene_path: Path) -> None:
    config = load_scene(tabletop_scene_path)
    a, b, c = World(config, 7), World(config, 7), World(config, 8)
    pa = [GroundTruthOracle(a).T_world_object(n) for n in a.objects]
    pb = [GroundTruthOracle(b).T_world_object(n) for n in b.objects]
    pc = [GroundTruthOracle(c).T_world_object(n) for n in c.objects]
    assert len(pa) == len(config.objects) > 0  # all() over no objects would prove nothing
    assert all(np.array_equal(x, y) for x, y in zip(pa, pb, strict=True))
    assert not all(np.allclose(x, y) for x, y in zip(pa, pc, strict=True))
    ca, da = a.camera.render_true()
    cb, db = b.camera.render_true()
    assert np.array_equal(da, db) and np.array_equal(ca, cb), "bit-identical depth before noise"
    fa, fb = a.camera.capture(), b.camera.capture()
    assert fa is not None and fb is not None
    assert np.array_equal(fa.depth_m, fb.depth_m) and np.array_equal(fa.color, fb.color), "same noise given the seed"


def test_scene_render_cli_writes_three_files(tabletop_scene_path: Path, tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "bt_grasp.cli.main",
            "scene",
            "render",
            str(tabletop_scene_path),
            "--seed",
            "0",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    import cv2

    color = cv2.imread(str(tmp_path / "color.png"))
    depth = cv2.imread(str(tmp_path / "depth.png"))
    info = json.loads((tmp_path / "camera.json").read_text())
    assert color.shape == (480, 640, 3) and depth.shape == (480, 640, 3)
    assert info["mount"] == "eye-to-hand" and info["intrinsics"]["cx_px"] == 319.5
    # the objects are visible: red, green and blue pixels exist (BGR in OpenCV)
    b, g, r = (color[..., i].astype(int) for i in range(3))
    assert ((r > 150) & (g < 60) & (b < 60)).sum() > 200
    assert ((g > 120) & (r < 80) & (b < 100)).sum() > 200
    assert ((b > 150) & (r < 60) & (g < 100)).sum() > 200


def test_an_async_frame_shows_the_scene_when_it_was_started(tabletop_scene_path: Path) -> None:
    """The log's extra frames are read back while the world steps on: the picture is the moment of the call."""
    a = World.from_file(tabletop_scene_path, seed=4)
    b = World.from_file(tabletop_scene_path, seed=4)
    target = a.robot.joint_positions() + np.array([0.6, -0.3, 0.4, 0.0, 0.5, 0.0])
    for w in (a, b):
        w.step(20)
        w.robot.set_joint_targets(target)
    picture = a.camera.render_color_async()
    a.step(60)  # the arm moves while the picture is read back
    reference = b.camera.render_color()  # b stands where a stood at the call
    np.testing.assert_array_equal(picture.result(), reference)
    b.step(60)
    moved = b.camera.render_color()
    assert np.abs(moved.astype(int) - reference.astype(int)).max() > 50  # the arm did move in view
    np.testing.assert_array_equal(a.camera.render_color(), moved)  # a sync render waits, then sees the present


def test_the_log_frames_look_like_the_pipelines_frames(world: World) -> None:
    """The log's colour frames come from a second camera with a cheaper shader: the same picture."""
    color, _ = world.camera.render_true()
    log_color = world.camera.render_color(fast_shader=True)
    assert log_color.shape == color.shape
    difference = np.abs(log_color.astype(int) - color.astype(int))
    assert difference.max() <= 8 and (difference.max(axis=-1) > 3).mean() < 1e-4


def test_the_log_cameras_8_bit_colour_leaves_later_cameras_float(tabletop_scene_path: Path) -> None:
    """The log camera is made with 8-bit colour, a global renderer setting: restored at once, so a camera made
    afterwards (the next episode's pipeline camera) still reads float colour and sees the same picture."""
    a = World.from_file(tabletop_scene_path, seed=2)
    before, _ = a.camera.render_true()
    logged = a.camera.render_color(fast_shader=True)
    assert logged.dtype == np.uint8 and logged.shape == before.shape
    b = World.from_file(tabletop_scene_path, seed=2)
    after, _ = b.camera.render_true()
    np.testing.assert_array_equal(after, before)


def test_arm_readings_are_taken_once_per_step_and_follow_every_step(tabletop_scene_path: Path) -> None:
    """The arm is read from SAPIEN once per physics step (the executor, the log and the gripper share it): every
    reading must still be what SAPIEN says now, after steps and a reset, and a caller writing to the array it was
    given changes no later reading."""
    world = World.from_file(tabletop_scene_path, seed=0)
    robot = world.robot

    def sapien_now() -> tuple[np.ndarray, np.ndarray, float]:
        qpos = robot.articulation.get_qpos()
        qvel = np.asarray(robot.articulation.get_qvel(), dtype=float)
        arm = robot._arm_idx
        return (np.asarray(qpos, dtype=float)[arm], qvel[arm],
                float(qpos[robot._finger_idx] + qpos[robot._mimic_idx]))

    home = robot.joint_positions()
    home[:] = 99.0
    assert not np.any(robot.joint_positions() == 99.0)
    robot.set_joint_targets(robot.joint_positions() + 0.3)
    robot.close_gripper()
    seen = []
    for _ in range(4):
        q, qd, width = sapien_now()
        assert np.array_equal(robot.joint_positions(), q) and np.array_equal(robot.joint_velocities(), qd)
        assert robot.gripper_width_m() == width
        seen.append(q)
        world.step(3)
    assert not np.array_equal(seen[0], seen[-1])  # the arm moved, and the readings followed it
    moved = robot.joint_positions()  # read before the reset: the reset must not leave this reading behind
    robot.reset(seen[0])
    assert not np.allclose(moved, seen[0], atol=1e-3)
    assert np.array_equal(robot.joint_positions(), sapien_now()[0])
    assert np.allclose(robot.joint_positions(), seen[0], atol=1e-6)
