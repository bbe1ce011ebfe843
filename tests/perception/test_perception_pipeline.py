"""perceive() on analytic synthetic frames: statuses for bad input, geometry, and use of the calibration."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from perception_synth import DEFAULT_T_BASE_CAMERA, RED, Box, render

from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import PerceptionStatus

CONFIG = PerceptionConfig()
BLUE = (69, 105, 195)


def test_no_frame_is_no_depth() -> None:
    result = perceive(None, DEFAULT_T_BASE_CAMERA, CONFIG)
    assert result.status is PerceptionStatus.NO_DEPTH
    assert "no frame" in result.message


def test_empty_depth_image_is_no_depth() -> None:
    frame = render([])
    empty = dataclasses.replace(frame, depth_m=np.zeros((0, 0), dtype=np.float32))
    result = perceive(empty, DEFAULT_T_BASE_CAMERA, CONFIG)
    assert result.status is PerceptionStatus.NO_DEPTH
    assert "empty" in result.message


@pytest.mark.parametrize("fill", [0.0, np.nan, 50.0])
def test_all_invalid_depth_is_no_depth(fill: float) -> None:
    frame = render([])
    invalid = dataclasses.replace(frame, depth_m=np.full(frame.depth_m.shape, fill, dtype=np.float32))
    result = perceive(invalid, DEFAULT_T_BASE_CAMERA, CONFIG)
    assert result.status is PerceptionStatus.NO_DEPTH
    assert "no valid depth" in result.message


def test_camera_looking_away_is_no_points() -> None:
    T = DEFAULT_T_BASE_CAMERA.copy()
    T[:3, 3] += [0.0, 3.0, 0.0]  # the calibration puts the camera's view off the workspace
    result = perceive(render([]), T, CONFIG)
    assert result.status is PerceptionStatus.NO_POINTS


def test_empty_table_is_no_objects() -> None:
    result = perceive(render([], noise_m=0.002), DEFAULT_T_BASE_CAMERA, CONFIG)
    assert result.status is PerceptionStatus.NO_OBJECTS
    assert result.table_plane_base is not None
    assert abs(result.table_plane_base[3]) < 0.003  # the table top is base z = 0


def test_wrong_colour_is_no_match() -> None:
    result = perceive(render([Box((0.5, 0.0), (0.05, 0.05, 0.05))]), DEFAULT_T_BASE_CAMERA, CONFIG, "green")
    assert result.status is PerceptionStatus.NO_MATCH
    assert len(result.others) == 1 and result.others[0].label == "red"


def test_unknown_colour_name_is_an_error() -> None:
    with pytest.raises(ValueError, match="unknown colour 'mauve'"):
        perceive(render([]), DEFAULT_T_BASE_CAMERA, CONFIG, "mauve")


def test_box_geometry_and_colour_selection() -> None:
    boxes = [Box((0.52, 0.08), (0.06, 0.035, 0.05), np.deg2rad(25.0), RED),
             Box((0.45, -0.12), (0.04, 0.04, 0.08), 0.0, BLUE)]
    result = perceive(render(boxes, noise_m=0.002), DEFAULT_T_BASE_CAMERA, CONFIG, "red")
    assert result.ok, result.message
    assert len(result.others) == 2
    det = result.best
    assert det is not None and det.label == "red"
    assert np.linalg.norm(det.centroid - [0.52, 0.08, 0.025]) < 0.003
    assert det.size_m == pytest.approx((0.06, 0.035, 0.05), abs=0.004)
    assert np.rad2deg(det.yaw_rad) == pytest.approx(25.0, abs=2.0)
    assert det.shape == "box"
    u0, v0, u1, v1 = det.pixel_box
    assert 0 <= u0 < u1 < 640 and 0 <= v0 < v1 < 480
    assert set(result.timings_ms) >= {"cloud", "roi", "voxel", "plane", "outliers", "cluster", "geometry", "total"}


def test_shifted_calibration_moves_the_detection() -> None:
    """A calibration 3 cm off in x moves every perceived position 3 cm: the pipeline uses the calibration."""
    frame = render([Box((0.5, 0.0), (0.05, 0.05, 0.05))])
    good = perceive(frame, DEFAULT_T_BASE_CAMERA, CONFIG, "red")
    wrong_T = DEFAULT_T_BASE_CAMERA.copy()
    wrong_T[0, 3] += 0.03
    wrong = perceive(frame, wrong_T, CONFIG, "red")
    assert good.best is not None and wrong.best is not None
    assert wrong.best.centroid - good.best.centroid == pytest.approx([0.03, 0.0, 0.0], abs=5e-4)
