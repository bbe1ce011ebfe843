"""Cell files (issue 41): version 2 is loaded strictly like a scene, names what a run needs and nothing it cannot
check; the scene the leaves read from it is the installation without objects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.cell.format import load_cell, pose_to_T
from bt_grasp.episode.cell_scene import scene_for_cell
from bt_grasp.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "cells" / "example-ur5.yaml"


def test_the_shipped_example_loads_and_becomes_a_scene_without_objects() -> None:
    cell = load_cell(EXAMPLE)
    scene = scene_for_cell(cell)
    assert scene.objects == () and scene.goal is None and not scene.camera.noise.enabled
    assert scene.physics.control_rate_hz == 125.0  # the controller's period: one tick per servoJ target
    h = cell.table_plane.height_m
    assert np.allclose(scene.T_world_base()[:3, 3], [0.0, 0.0, -h])  # the world's origin on the table top
    assert scene.robot.home_q_rad == cell.arm.home_q_rad
    assert scene.workspace.z_max_m == cell.workspace.objects_up_to_m


def _write(tmp_path: Path, old: str, new: str) -> Path:
    text = EXAMPLE.read_text()
    assert old in text, old
    path = tmp_path / "cell.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(("old", "new", "expected"), [
    ("  payload_kg:", "  payload_kgs:", r"cell.yaml:\d+: .*payload_kgs"),
    ("version: 2", "version: 1", r"cell.yaml:\d+: is a version 1 cell file .*write it again"),
    ("  normal: [0.0, 0.0, 1.0]", "  normal: [0.0, 0.2, 1.0]", r"tilted 11.3 degrees"),
    ("  joint_speed_cap_rad_s: 0.5", "  joint_speed_cap_rad_s: 4.0", r"joint_speed_cap_rad_s"),
    ("  kind: realsense", "  kind: recording", r"needs the recording's path"),
])
def test_a_bad_cell_file_is_one_sentence_naming_file_and_line(tmp_path: Path, old: str, new: str,
                                                                expected: str) -> None:
    with pytest.raises(ConfigError, match=expected) as caught:
        load_cell(_write(tmp_path, old, new))
    assert "\n" not in str(caught.value)


def test_a_ur_pose_is_a_rotation_vector() -> None:
    T = pose_to_T((0.1, 0.2, 0.3, 0.0, 0.0, np.pi / 2))
    assert np.allclose(T[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    assert np.allclose(T[:3, 3], [0.1, 0.2, 0.3])
    assert np.allclose(pose_to_T((0, 0, 0, 0, 0, 0)), np.eye(4))
