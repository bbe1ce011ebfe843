"""The learned detector's boxes joined with depth on synthetic RGB-D frames (the perception tests' ray caster,
no simulator, no network): a box selects the cluster it covers, cuts a cluster of touching objects, drops a box
over bare table, and its long axis decides the yaw the grasp closes across.

The boxes are made the way a network would draw them: around the object's projected corners in the image
(``cv2.minAreaRect``), a little loose; the expected numbers are the synthetic objects' true poses."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from perception.perception_synth import DEFAULT_T_BASE_CAMERA, INTRINSICS, Box, render

from bt_grasp.perception.grasps import synthesize_grasps
from bt_grasp.perception.learned import SURE_SCORE, TENTATIVE_SCORE, join_boxes, long_axis_yaw, orient_along
from bt_grasp.perception.pipeline import perceive
from bt_grasp.perception.results import PerceptionStatus
from bt_grasp.perception.segment import Plane

from .synthetic_boxes import image_box


def _deg(yaw: float) -> float:
    return math.degrees(yaw) % 180.0


PEN = Box((0.45, 0.06), (0.14, 0.03, 0.04), math.radians(30.0))
CUBE = Box((0.50, -0.12), (0.05, 0.05, 0.05))


def test_each_box_names_the_cluster_it_covers_and_its_long_axis_feeds_the_grasp() -> None:
    frame = render([PEN, CUBE])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    boxes = [image_box(CUBE, "box", 0.6), image_box(PEN, "pen", 0.9)]
    result = join_boxes(geometric, boxes, frame, DEFAULT_T_BASE_CAMERA)
    assert result.status is PerceptionStatus.OK
    assert [(d.class_name, d.class_score) for d in result.detections] == [("pen", 0.9), ("box", 0.6)]
    pen, cube = result.detections
    assert pen.centroid_base_m[:2] == pytest.approx(PEN.centre_xy, abs=0.005)
    assert cube.centroid_base_m[:2] == pytest.approx(CUBE.centre_xy, abs=0.005)
    assert _deg(pen.yaw_rad) == pytest.approx(30.0, abs=1.5) and pen.size_m[0] == pytest.approx(0.14, abs=0.01)
    assert len(result.others) == 2 and {d.class_name for d in result.others} == {"pen", "box"}
    best = synthesize_grasps(pen, result.others).best
    assert best is not None
    closing = best.T_base_tcp_grasp[:3, 1]  # tcp y: the direction the pads close along
    assert abs(float(closing[:2] @ [math.cos(PEN.yaw_rad), math.sin(PEN.yaw_rad)])) < math.sin(math.radians(3))


def test_a_cluster_of_two_touching_objects_is_cut_by_their_boxes() -> None:
    left, right = Box((0.45, 0.025), (0.06, 0.05, 0.05)), Box((0.45, -0.025), (0.06, 0.05, 0.05))
    frame = render([left, right])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    assert len(geometric.others) == 1  # one cluster: equal heights, touching: nothing to cut it at
    result = join_boxes(geometric, [image_box(left, "can", 0.8, grow=1.0), image_box(right, "mug", 0.7, grow=1.0)],
                        frame, DEFAULT_T_BASE_CAMERA)
    named = {d.class_name: d for d in result.detections}
    assert set(named) == {"can", "mug"} and len(result.others) == 2
    assert named["can"].centroid_base_m[1] == pytest.approx(0.025, abs=0.008)
    assert named["mug"].centroid_base_m[1] == pytest.approx(-0.025, abs=0.008)
    assert "cut out of a cluster by a can box" in named["can"].cluster_note


def test_a_box_over_bare_table_names_nothing_and_an_unnamed_object_is_kept_for_clearance() -> None:
    frame = render([PEN, CUBE])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    ghost = image_box(Box((0.40, -0.25), (0.05, 0.05, 0.05)), "mug", 0.95)  # nothing stands there
    result = join_boxes(geometric, [ghost, image_box(PEN, "pen", 0.5)], frame, DEFAULT_T_BASE_CAMERA)
    assert [d.class_name for d in result.detections] == ["pen"]
    unnamed = [d for d in result.others if not d.class_name]
    assert len(unnamed) == 1 and unnamed[0].centroid_base_m[:2] == pytest.approx(CUBE.centre_xy, abs=0.005)
    none = join_boxes(geometric, [ghost], frame, DEFAULT_T_BASE_CAMERA)
    assert none.status is PerceptionStatus.NO_MATCH and len(none.others) == 2 and not none.detections
    assert "the detector named none of them (1 box(es))" in none.message


def test_a_colour_keeps_only_named_objects_of_that_colour() -> None:
    frame = render([PEN, replace(CUBE, rgb=(40, 60, 200))])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    boxes = [image_box(PEN, "pen", 0.5), image_box(CUBE, "box", 0.9)]
    result = join_boxes(geometric, boxes, frame, DEFAULT_T_BASE_CAMERA, color="red")
    assert [d.class_name for d in result.detections] == ["pen"]


def test_a_box_far_off_the_footprints_axis_turns_the_yaw_to_its_own() -> None:
    block = Box((0.48, 0.0), (0.12, 0.07, 0.03))  # the footprint's long axis: base x (yaw 0)
    frame = render([block])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    assert _axis_gap_deg(geometric.others[0].yaw_rad, 0.0) < 2.0
    box = image_box(block, "book", 0.8)
    turned = replace(box, angle_rad=box.angle_rad + math.radians(40.0))  # the network says: 40 degrees off
    yaw_box = long_axis_yaw(turned, DEFAULT_T_BASE_CAMERA, INTRINSICS, 0.015)
    assert yaw_box is not None and _axis_gap_deg(yaw_box, 0.0) > 20.0
    result = join_boxes(geometric, [turned], frame, DEFAULT_T_BASE_CAMERA)
    (named,) = result.detections
    assert _axis_gap_deg(named.yaw_rad, yaw_box) < 0.01
    along = 0.12 * abs(math.cos(yaw_box)) + 0.07 * abs(math.sin(yaw_box))  # the rectangle's extent along that axis
    assert named.size_m[0] == pytest.approx(along, abs=0.01) and named.size_m[0] >= named.size_m[1]
    agreeing = join_boxes(geometric, [box], frame, DEFAULT_T_BASE_CAMERA).detections[0]
    assert _deg(agreeing.yaw_rad) == pytest.approx(_deg(geometric.others[0].yaw_rad), abs=1e-9)


def _axis_gap_deg(a: float, b: float) -> float:
    d = abs(math.degrees(a - b)) % 180.0
    return min(d, 180.0 - d)


def test_orient_along_measures_the_footprint_along_the_given_axis() -> None:
    frame = render([Box((0.48, 0.0), (0.10, 0.08, 0.04))])
    det = perceive(frame, DEFAULT_T_BASE_CAMERA).others[0]
    plane = Plane(np.array([0.0, 0.0, 1.0]), 0.0)
    turned = orient_along(det, math.radians(20.0), plane)
    assert turned.yaw_rad == pytest.approx(math.radians(20.0))
    # a 10 x 8 cm rectangle measured along 20 degrees: 10 cos 20 + 8 sin 20 = 12.1 cm (visible points: a bit less)
    assert turned.size_m[0] == pytest.approx(0.10 * math.cos(math.radians(20)) + 0.08 * math.sin(math.radians(20)),
                                             abs=0.008)
    assert turned.obb is not None and turned.obb.axes[0][:2] == pytest.approx(
        (math.cos(math.radians(20)), math.sin(math.radians(20))), abs=1e-9)
    assert orient_along(det, math.radians(90.0), plane) is det  # 8 cm along, 10 across: the points disagree


PLATE = Box((0.45, 0.05), (0.16, 0.16, 0.03))
TOUCHING_CUBE = Box((0.45, -0.05), (0.04, 0.04, 0.03))  # touches the plate's edge, as tall: one cluster


def test_a_surer_box_does_not_take_a_touching_object_another_box_names() -> None:
    frame = render([PLATE, TOUCHING_CUBE])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    assert len(geometric.others) == 1  # the plate's box covers over 80 % of this cluster, the cube's corner too
    boxes = [image_box(PLATE, "plate", 0.9), image_box(TOUCHING_CUBE, "small_box", 0.6)]
    result = join_boxes(geometric, boxes, frame, DEFAULT_T_BASE_CAMERA)
    named = {d.class_name: d for d in result.detections}
    assert set(named) == {"plate", "small_box"} and len(result.others) == 2
    assert named["plate"].centroid_base_m[:2] == pytest.approx(PLATE.centre_xy, abs=0.008)
    assert named["plate"].size_m[0] == pytest.approx(0.16, abs=0.01)
    assert named["small_box"].centroid_base_m[1] == pytest.approx(-0.05, abs=0.012)
    alone = join_boxes(geometric, boxes[:1], frame, DEFAULT_T_BASE_CAMERA)  # no box names the cube: the whole
    assert alone.detections[0].size_m[0] == pytest.approx(0.19, abs=0.01)  # cluster, as the geometry sees it


def test_a_second_box_over_the_same_object_does_not_split_it() -> None:
    """Networks often draw two boxes over one object (two classes, or one a little larger); the rule above is
    about a box mostly elsewhere, so the surer box still takes the whole object, and the other names nothing."""
    frame = render([PEN, CUBE])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    for second in (image_box(CUBE, "mug", 0.5, grow=1.5), image_box(CUBE, "mug", 0.5, grow=1.3, turn_rad=0.3)):
        result = join_boxes(geometric, [image_box(CUBE, "box", 0.9, grow=0.95), second], frame,
                            DEFAULT_T_BASE_CAMERA)
        assert [d.class_name for d in result.detections] == ["box"] and len(result.others) == 2
        assert result.detections[0].size_m[:2] == pytest.approx((0.05, 0.05), abs=0.006)


def test_a_box_under_the_sure_score_names_only_a_whole_object_no_surer_box_named() -> None:
    frame = render([PEN, CUBE])
    geometric = perceive(frame, DEFAULT_T_BASE_CAMERA)
    assert TENTATIVE_SCORE < SURE_SCORE
    low_pen = image_box(PEN, "pen", 0.15)
    result = join_boxes(geometric, [image_box(CUBE, "box", 0.9), low_pen], frame, DEFAULT_T_BASE_CAMERA)
    assert [(d.class_name, d.class_score) for d in result.detections] == [("box", 0.9), ("pen", 0.15)]
    assert "under the sure score" in result.detections[1].cluster_note
    # a low box over an object a sure box named does not rename it, nor cut it
    mug = image_box(CUBE, "mug", 0.2)
    again = join_boxes(geometric, [image_box(CUBE, "box", 0.9), mug], frame, DEFAULT_T_BASE_CAMERA)
    assert [d.class_name for d in again.detections] == ["box"] and len(again.others) == 2
    # a low box over bare table, or over a part of an object only, names nothing
    ghost = image_box(Box((0.40, -0.25), (0.05, 0.05, 0.05)), "mug", 0.2)
    half_pen = image_box(replace(PEN, size=(0.03, 0.03, 0.04)), "pen", 0.2)  # a small part of the pen
    none = join_boxes(geometric, [ghost, half_pen], frame, DEFAULT_T_BASE_CAMERA)
    assert none.status is PerceptionStatus.NO_MATCH and not none.detections and len(none.others) == 2
    # a weak box is often short of the object's ends: over most of an unnamed object it names all of it
    short_pen = image_box(replace(PEN, size=(0.10, 0.03, 0.04)), "pen", 0.2)
    (pen,) = join_boxes(geometric, [short_pen], frame, DEFAULT_T_BASE_CAMERA).detections
    assert pen.size_m[0] == pytest.approx(0.14, abs=0.01) and pen.class_score == 0.2
    # a sure box still cuts: the rule for low boxes is only that they take whole objects
    assert join_boxes(geometric, [image_box(PEN, "pen", 0.3)], frame, DEFAULT_T_BASE_CAMERA).detections
