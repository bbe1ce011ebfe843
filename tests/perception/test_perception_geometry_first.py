"""Geometry first, colour as an attribute (issue 28): synthetic frames (no simulator) of objects whose colour
is the table's or no named colour at all; every detection carries its oriented boxes and principal axis."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.perception.cloud import PixelCloud
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import Detection, ShapeClass
from bt_grasp.perception.segment import Plane
from bt_grasp.perception.split import split_touching
from tests.perception.perception_synth import DEFAULT_T_BASE_CAMERA, WOOD, Box, render

CONFIG = PerceptionConfig()


def _only(boxes: list[Box]) -> tuple[Detection, ...]:
    result = perceive(render(boxes, noise_m=0.0005, seed=3), DEFAULT_T_BASE_CAMERA, CONFIG)
    assert result.ok, result.message
    return result.others


@pytest.mark.parametrize("rgb", [WOOD, (20, 20, 20), (240, 240, 240)], ids=["table-coloured", "black", "white"])
def test_an_object_of_any_colour_is_found_by_geometry(rgb: tuple[int, int, int]) -> None:
    (det,) = _only([Box((0.45, 0.05), (0.06, 0.04, 0.05), 0.3, rgb)])
    assert np.linalg.norm(det.centroid - [0.45, 0.05, 0.025]) < 0.004
    assert det.color_rgb == pytest.approx(rgb, abs=12)
    assert det.shape_class is ShapeClass.BOX_LIKE
    assert det.obb is not None and det.obb_pca is not None and det.points_base_m is not None
    assert det.obb.extents_m == pytest.approx((0.06, 0.04, 0.05), abs=0.004)
    assert det.obb.center_m == det.centroid_base_m
    assert np.allclose(det.obb.rotation.T @ det.obb.rotation, np.eye(3), atol=1e-9)
    assert np.linalg.det(det.obb_pca.rotation) == pytest.approx(1.0)
    assert det.points_base_m.shape == (det.point_count, 3) and not det.points_base_m.flags.writeable


def test_colour_is_an_attribute_not_the_key() -> None:
    grey, red = _only([Box((0.45, 0.10), (0.05, 0.05, 0.05), 0.0, WOOD), Box((0.45, -0.10), (0.05, 0.05, 0.05))])[:2]
    names = sorted([(d.centroid_base_m[1] > 0, d.color_name, d.label) for d in (grey, red)])
    assert names[1][0] and names[1][2] == "object"  # no named colour covers the table-coloured box: found anyway
    assert names[0][1:] == ("red", "red")


def test_elongated_object_has_its_principal_axis_along_its_length() -> None:
    yaw = 0.5
    (det,) = _only([Box((0.45, 0.0), (0.20, 0.02, 0.02), yaw, WOOD)])
    assert det.shape_class is ShapeClass.ELONGATED
    axis = np.asarray(det.principal_axis_base)
    assert abs(axis @ [np.cos(yaw), np.sin(yaw), 0.0]) > np.cos(np.radians(3))
    assert det.extents_m[0] == pytest.approx(0.20, abs=0.01)
    assert det.obb is not None and det.obb.extents_m[0] == pytest.approx(0.20, abs=0.006)


def test_a_thin_wide_object_is_flat() -> None:
    (det,) = _only([Box((0.45, 0.0), (0.12, 0.10, 0.015), 0.2, (230, 230, 230))])
    assert det.shape_class is ShapeClass.FLAT


def test_touching_objects_of_different_heights_are_split() -> None:
    tall = Box((0.45, 0.03), (0.05, 0.05, 0.08), 0.0, WOOD)
    low = Box((0.45, -0.025), (0.05, 0.06, 0.03), 0.0, WOOD)  # its +y face touches the tall box's -y face
    dets = _only([tall, low])
    assert len(dets) == 2, [d.centroid_base_m for d in dets]
    by_y = sorted(dets, key=lambda d: d.centroid_base_m[1])
    assert [d.split_from for d in by_y] == [2, 2]
    assert by_y[0].size_m[2] == pytest.approx(0.03, abs=0.004) and by_y[1].size_m[2] == pytest.approx(0.08, abs=0.004)
    assert by_y[0].centroid_base_m[1] == pytest.approx(-0.025, abs=0.006)
    assert by_y[1].centroid_base_m[1] == pytest.approx(0.03, abs=0.006)


def test_touching_objects_of_one_height_stay_one_cluster_nothing_to_cut() -> None:
    dets = _only([Box((0.45, 0.025), (0.05, 0.05, 0.05), 0.0, WOOD), Box((0.45, -0.025), (0.05, 0.05, 0.05))])
    assert len(dets) == 1 and dets[0].split_from == 0
    assert dets[0].size_m[:2] == pytest.approx((0.10, 0.05), abs=0.005)


def _box_surface(lo: tuple[float, float, float], hi: tuple[float, float, float], step: float = 0.002) -> np.ndarray:
    """Points on a box's top face and its +x side (the side facing a camera at +x)."""
    xs, ys, zs = (np.arange(a, b + 1e-9, step) for a, b in zip(lo, hi, strict=True))
    top = np.array([(x, y, hi[2]) for x in xs for y in ys])
    side = np.array([(hi[0], y, z) for y in ys for z in zs])
    return np.concatenate([top, side])


def test_stacked_objects_stay_one_cluster_with_a_reason() -> None:
    lower = _box_surface((0.40, -0.05, 0.0), (0.50, 0.05, 0.03))
    upper = _box_surface((0.425, -0.025, 0.03), (0.475, 0.025, 0.08))
    pts = np.concatenate([lower, upper])
    plane = Plane(np.array([0.0, 0.0, 1.0]), 0.0)
    cut = split_touching(PixelCloud(pts, np.zeros((len(pts), 2), dtype=np.int32)), plane, 30)
    assert len(cut.parts) == 1
    assert "30 mm above the table stands on (or behind) another" in cut.note
    side_by_side = np.concatenate([lower, upper + np.array([0.0, 0.075, -0.03])])  # the same two, next to each other
    cut = split_touching(PixelCloud(side_by_side, np.zeros((len(side_by_side), 2), dtype=np.int32)), plane, 30)
    assert len(cut.parts) == 2 and cut.note == ""
    # the cells along the shared edge hold both objects' points: at most 3 % change sides
    assert sorted(len(p) for p in cut.parts) == pytest.approx(sorted([len(lower), len(upper)]), abs=0.03 * len(pts))
