"""Calibration files: a round trip keeps the transform; every bad file is one ConfigError naming file:line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.geometry import T_from_xyz_rpy
from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.perception.calibration_file import load_calibration, make_calibration, save_calibration
from bt_grasp.perception.charuco import BoardSpec

HERE = Path(__file__).parent
BAD = HERE.parent / "data" / "bad_calibrations"

# file -> (line or None, fragment of the message)
EXPECTED: dict[str, tuple[int | None, str]] = {
    "other_mount.yaml": (2, "for an eye-in-hand camera, but the camera is mounted eye-to-hand"),
    "missing_method.yaml": (1, "missing required key 'method'"),
    "wrong_type.yaml": (14, "samples"),
    "unknown_key.yaml": (15, "unknown key 'samples_extra'"),
    "inconsistent_transform.yaml": (5, "describe different transforms"),
    "not_a_rotation.yaml": (5, "not a rotation"),
    "unknown_mount.yaml": (2, "mount"),
    "malformed.yaml": (9, "invalid YAML"),
    "empty.yaml": (None, "the file is empty"),
    "python_tag.yaml": (2, "unsupported YAML tag"),
    "bad_board.yaml": (19, "marker_m must be smaller than square_m"),
    "short_quaternion.yaml": (7, "quat_wxyz"),
}


def test_corpus_is_complete() -> None:
    assert sorted(p.name for p in BAD.glob("*.yaml")) == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_calibration_file(name: str) -> None:
    line, fragment = EXPECTED[name]
    with pytest.raises(ConfigError) as info:
        load_calibration(BAD / name, mount="eye-to-hand")
    message = str(info.value)
    prefix = f"{BAD / name}:{line}: " if line is not None else f"{BAD / name}: "
    assert message.startswith(prefix), message
    assert fragment in message


def test_missing_file() -> None:
    with pytest.raises(ConfigError, match="no such file"):
        load_calibration(HERE / "no_such_calibration.yaml")


def test_good_file_and_round_trip(tmp_path: Path) -> None:
    good = load_calibration(HERE / "good_calibration.yaml", mount="eye-to-hand")
    assert good.T_base_camera[:3, 3] == pytest.approx([1.05, 0.0, 0.75])
    T = T_from_xyz_rpy([-0.07, 0.0, 0.01], np.deg2rad([1.0, 12.0, -2.0]))
    intrinsics = CameraIntrinsics(640, 480, 600, 600, 319.5, 239.5)
    calib = make_calibration("eye-in-hand", T, "tool0", "park", 18, {}, intrinsics, BoardSpec())
    path = save_calibration(calib, tmp_path / "sub" / "calib.yaml")
    loaded = load_calibration(path, mount="eye-in-hand")
    assert np.allclose(loaded.T_parent_camera, T, atol=1e-12)
    T_base_tool = T_from_xyz_rpy([0.4, 0.1, 0.5], [np.pi, 0.0, 0.3])
    assert np.allclose(loaded.T_base_camera_at(T_base_tool), T_base_tool @ T)
    assert np.allclose(loaded.T_tool_camera, T) and loaded.tool_link == "tool0"
    with pytest.raises(ValueError, match="needs T_base_tool"):
        loaded.T_base_camera_at()
