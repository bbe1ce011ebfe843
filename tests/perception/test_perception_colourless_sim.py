"""Perception without colour in the simulator (issue 28): objects of any colour found by geometry, their
oriented boxes and principal axes judged against the oracle's truth, touching objects split. One capture per
scene (tests/data/scenes/colourless.yaml, touching.yaml), a perfect calibration from the oracle so the
figures are perception's own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import Detection, PerceptionResult, ShapeClass

pytestmark = pytest.mark.sim

SCENES = Path(__file__).resolve().parents[1] / "data" / "scenes"


def _capture(name: str) -> tuple[PerceptionResult, dict[str, np.ndarray]]:
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    world = World.from_file(SCENES / name, 0)
    oracle = GroundTruthOracle(world)
    world.step(world.steps_per_tick * 10)
    frame = world.camera.capture()
    result = perceive(frame, oracle.T_base_camera_cv(), PerceptionConfig.for_scene(world.config))
    return result, {o.name: oracle.T_base_object(o.name) for o in world.config.objects}


@pytest.fixture(scope="module")
def colourless() -> tuple[PerceptionResult, dict[str, np.ndarray]]:
    return _capture("colourless.yaml")


def _at(result: PerceptionResult, T_true: np.ndarray) -> Detection:
    """The one detection whose centre lies within 1 cm of the object's origin in x, y."""
    near = [d for d in result.others if np.hypot(*(np.asarray(d.centroid_base_m[:2]) - T_true[:2, 3])) < 0.01]
    assert len(near) == 1, f"{len(near)} detections near {T_true[:2, 3]}: {[d.centroid_base_m for d in result.others]}"
    return near[0]


@pytest.mark.parametrize(
    ("name", "shape_class", "color_names"),
    [
        ("grey_box", ShapeClass.BOX_LIKE, ("grey",)),  # grey on the grey table
        ("black_cylinder", ShapeClass.CYLINDER_LIKE, ("black",)),
        ("white_box", ShapeClass.BOX_LIKE, ("white",)),
        ("two_colour_block", ShapeClass.BOX_LIKE, ("red", "blue")),  # its file's own two materials
        ("grey_pen", ShapeClass.ELONGATED, ("grey",)),  # the household pen, grey on grey
    ],
)
def test_every_object_is_found_whatever_its_colour(
    colourless: tuple[PerceptionResult, dict[str, np.ndarray]], name: str, shape_class: ShapeClass,
    color_names: tuple[str, ...],
) -> None:
    result, truth = colourless
    assert result.ok and len(result.others) == 5, result.message
    det = _at(result, truth[name])
    assert det.shape_class is shape_class
    assert det.color_name in color_names
    assert det.obb is not None and det.obb_pca is not None and det.points_base_m is not None
    assert len(det.points_base_m) == det.point_count > 300
    # the visible points lie inside the gravity-aligned box (grown by 5 mm for the depth noise)
    local = (det.points_base_m - det.obb.center_m) @ det.obb.rotation
    inside = np.all(np.abs(local) <= np.asarray(det.obb.extents_m) / 2 + 0.005, axis=1)
    assert inside.mean() > 0.97


def test_the_elongated_objects_box_and_axis_match_the_truth(
    colourless: tuple[PerceptionResult, dict[str, np.ndarray]],
) -> None:
    result, truth = colourless
    T_pen = truth["grey_pen"]
    det = _at(result, T_pen)
    long_axis = T_pen[:3, 0]  # the pen's mesh is 146 mm along its x, 14 x 12 mm across
    angle = np.degrees(np.arccos(min(1.0, abs(float(np.dot(det.principal_axis_base, long_axis))))))
    assert angle < 3.0, f"principal axis {angle:.1f} deg off the pen's length"
    assert det.obb is not None and det.obb_pca is not None
    assert np.degrees(np.arccos(min(1.0, abs(float(det.obb.axes[0] @ long_axis))))) < 3.0
    assert det.obb.extents_m[0] == pytest.approx(0.146, abs=0.012)
    assert det.obb.extents_m[2] == pytest.approx(0.012, abs=0.004)
    assert det.extents_m[0] == pytest.approx(0.146, abs=0.012) and det.extents_m[1] < 0.02
    assert det.obb_pca.axes[0] == det.principal_axis_base
    # the centre of the pen (its mesh origin is the bottom centre of its 146 mm, 12 mm high)
    centre = T_pen[:3, 3] + np.array([0.0, 0.0, 0.006])
    assert np.linalg.norm(np.asarray(det.centroid_base_m) - centre) < 0.008


def test_touching_boxes_are_split_at_their_height_step_and_one_height_stays_one() -> None:
    result, truth = _capture("touching.yaml")
    assert result.ok, result.message
    low, tall = _at(result, truth["low_box"]), _at(result, truth["tall_box"])
    assert low is not tall and low.split_from == tall.split_from == 2
    assert low.size_m[2] == pytest.approx(0.03, abs=0.004) and tall.size_m[2] == pytest.approx(0.08, abs=0.004)
    for det, name in ((low, "low_box"), (tall, "tall_box")):
        assert np.linalg.norm(det.centroid - truth[name][:3, 3]) < 0.006
    # two 5 cm boxes of one height side by side: no step to cut, reported as one 10 x 5 cm object
    pair_centre = (truth["left_box"][:3, 3] + truth["right_box"][:3, 3]) / 2
    (pair,) = [d for d in result.others if np.hypot(*(d.centroid[:2] - pair_centre[:2])) < 0.01]
    assert pair.split_from == 0 and pair.size_m[:2] == pytest.approx((0.10, 0.05), abs=0.006)
    assert len(result.others) == 3
