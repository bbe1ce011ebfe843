"""Object queries: PerceiveAll, SelectObject, ObjectPose, ObjectCount, and FixturePose.

A perceived object is a :class:`bt_grasp.perception.results.Detection` (base frame; ``label`` is its colour
name, ``color_name`` its dominant colour, ``shape`` "box" or "round", ``shape_class`` box-like,
cylinder-like, elongated, flat or other, ``size_m`` length/width/height, ``class_name`` the learned detector's
class, "" when it named none). Objects are found by geometry; colour, shape class, size and (with
``detector="learned"``) class are attributes to choose by. A list of them (an *object list*) is a tuple of
detections; the object loop (``ForEachObject``) walks one. Poses are :class:`bt_grasp.behaviours.pose.Pose`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, TypeGuard

import numpy as np

from bt_grasp.behaviours.attempts import AttemptMemory
from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.perceive import DETECTOR_PORTS, DetectorLeaf
from bt_grasp.behaviours.pose import Pose
from bt_grasp.behaviours.reasons import PERCEPTION_REASONS, FailureReason
from bt_grasp.detector.kinds import DetectorKind, parse_detector
from bt_grasp.errors import TreeFileError, did_you_mean
from bt_grasp.tree.node_api import Leaf, Status, action, condition, input_port, output_port

if TYPE_CHECKING:
    from collections.abc import Iterable

    from bt_grasp.perception.results import Detection
    from bt_grasp.scene.fixtures import Fixture
    from bt_grasp.scene.format import Scene
    from bt_grasp.tree.node import BtNode

_OBJECTS_IN = input_port("objects", object, "{objects}", "an object list (from PerceiveAll)")
ORDERS = ("first", "nearest", "farthest", "largest", "smallest")
ANY = "any"  # an explicit "no filter" for colour, shape and shape class (the same as leaving it empty)
SHAPES = ("", ANY, "box", "round")
SHAPE_CLASSES = ("", ANY, "box-like", "cylinder-like", "elongated", "flat", "other")


def is_detection(value: object) -> TypeGuard[Detection]:
    return all(hasattr(value, a) for a in ("centroid_base_m", "size_m", "yaw_rad", "label"))


def object_list(value: object) -> tuple[Detection, ...] | None:
    """The value as a tuple of detections, or None when it is not an object list."""
    if is_detection(value):
        return (value,)
    if isinstance(value, Sequence) and not isinstance(value, str):
        items = tuple(value)
        return tuple(v for v in items if is_detection(v)) if all(is_detection(v) for v in items) else None
    return None


def footprint_m2(det: Detection) -> float:
    return float(det.size_m[0] * det.size_m[1])


def _wanted(value: str) -> str:
    return "" if value == ANY else value


def shape_class_of(det: Detection) -> str:
    """The detection's shape class value ("other" for a hand-made detection without one)."""
    value = getattr(det, "shape_class", None)
    return str(getattr(value, "value", value or "other"))


def class_of(det: Detection) -> str:
    """The class the learned detector named the object ("" when none did, or a hand-made detection)."""
    return str(getattr(det, "class_name", "") or "")


def matches(det: Detection, color: str, shape: str, min_size_m: float, max_size_m: float,
            shape_class: str = "", class_name: str = "") -> bool:
    """Colour (its label or its dominant colour), shape, shape class, class (the learned detector's), and the
    footprint's long side within [min_size_m, max_size_m]; an empty or "any" colour, shape, shape class or class
    matches every object."""
    color, shape, shape_class, class_name = _wanted(color), _wanted(shape), _wanted(shape_class), _wanted(class_name)
    if color and color not in (det.label, getattr(det, "color_name", "")):
        return False
    if class_name and class_of(det) != class_name:
        return False
    if shape and det.shape != shape:
        return False
    if shape_class and shape_class_of(det) != shape_class:
        return False
    length = float(max(det.size_m[0], det.size_m[1]))
    return min_size_m <= length <= max_size_m


@action(
    ports=[
        output_port("objects", object, "every object seen, as an object list", default="{objects}"),
        *DETECTOR_PORTS,
    ],
    reasons=PERCEPTION_REASONS,
    needs_robot=True,
)
class PerceiveAll(DetectorLeaf):
    """Capture one RGB-D frame and list every object standing on the table (an empty list when none).

    With ``detector="learned"`` each object a box of the model covers carries the box's ``class_name`` and
    ``class_score`` (objects no box covered are listed too, without a class: they matter for clearance).
    FAILURE: CALIBRATION_MISSING (no calibration loaded), NO_FRAME (the camera returned nothing),
    NO_DETECTION (no table was found in the image at all), BAD_INPUT (a detector that is neither geometric nor
    learned).
    """

    def update(self) -> Status:
        detector = self.detector_now()
        if isinstance(detector, Status):
            return detector
        result = self.in_flight.poll(self, None, accept_empty=True, detector=detector)
        if isinstance(result, Status):
            return result  # RUNNING while the detections are on their way (the cell's latency), or FAILURE
        objects = tuple(result.others)
        self.ports.set("objects", objects)
        self.feedback_message = f"{len(objects)} object(s): " + ", ".join(class_of(d) or d.label for d in objects)
        return Status.SUCCESS


@action(
    ports=[
        _OBJECTS_IN,
        input_port("color", str, "", "only objects of this colour name (empty or any: any)"),
        input_port("shape", str, "", "only this footprint: box or round (empty or any: any)", choices=SHAPES),
        input_port("shape_class", str, "", "only this shape class: box-like, cylinder-like, elongated, flat, other "
                   "(empty or any: any)", choices=SHAPE_CLASSES),
        input_port("class", str, "", "only objects of this class of the learned detector's model, e.g. mug (empty or "
                   "any: any)"),
        input_port("min_size", float, 0.0, "only footprints whose long side is at least this, m"),
        input_port("max_size", float, 1.0, "only footprints whose long side is at most this, m"),
        input_port("order", str, "first", "which match: " + ", ".join(ORDERS), choices=ORDERS),
        input_port("point", Pose, "0;0",
                   "the point nearest/farthest measure from (a fixture: {pose} from FixturePose)"),
        input_port("failed_last_after", int, 0, "an object with at least this many failed attempts in this run "
                   "(grasps, placements) goes after the others, whatever the order (0: never)"),
        output_port("object", object, "the chosen object", default="{object}"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.NO_DETECTION),
)
class SelectObject(Leaf):
    """Choose one object from a list by colour, footprint shape, shape class, class and size (each empty or
    "any": every object), then by order (first in the list, nearest to or farthest from ``point`` -- a
    fixture's pose from FixturePose --, largest or smallest footprint). ``class`` names a class of the learned
    detector's model (objects from ``PerceiveAll detector="learned"``); a literal class the tree's model does not
    have is a load error with the closest name. With ``failed_last_after`` N > 0, an object the run failed on N
    times or more (the run's memory of its attempts) is chosen only when every other match failed as often: the
    next in the order is tried. FAILURE: NO_DETECTION (nothing matches; with a class, also when no object of the
    list was named by a learned detector), BAD_INPUT (``objects`` is not an object list)."""

    def setup(self, **kwargs: object) -> None:
        cell = kwargs.get("cell")
        #: the run's memory of its attempts, when the node runs in a cell (a dry run has none)
        self._memory: AttemptMemory | None = cell.attempts if isinstance(cell, Cell) else None

    def _failed_last(self, found: list[Detection]) -> tuple[list[Detection], int]:
        """``found`` with the objects that failed ``failed_last_after`` times or more left out (all of them, when
        every one did), and how many were left out."""
        after = self.ports.get("failed_last_after", int) or 0
        memory = getattr(self, "_memory", None)
        if after <= 0 or memory is None:
            return found, 0
        fresh = [d for d in found if memory.object_failures(d) < after]
        return (fresh, len(found) - len(fresh)) if fresh else (found, 0)

    def update(self) -> Status:
        objects = object_list(self.ports.get("objects"))
        if objects is None:
            return self.fail(FailureReason.BAD_INPUT.value, "'objects' is not an object list: run PerceiveAll first")
        color, shape = _wanted(self.ports.require("color", str)), _wanted(self.ports.require("shape", str))
        shape_class = _wanted(self.ports.require("shape_class", str))
        class_name = _wanted(self.ports.get("class", str) or "")
        if class_name and objects and not any(class_of(d) for d in objects):
            return self.fail(FailureReason.NO_DETECTION.value,
                             f"no {class_name} among {len(objects)} object(s): a learned detector named none of them "
                             f"(or they were perceived with the geometric detector)")
        lo, hi = self.ports.require("min_size", float), self.ports.require("max_size", float)
        found = [d for d in objects if matches(d, color, shape, lo, hi, shape_class, class_name)]
        if not found:
            wanted = " ".join(w for w in (color, class_name, shape_class, shape or "object") if w)
            seen = sorted({class_of(d) for d in objects if class_of(d)})
            classes = f" (classes seen: {', '.join(seen)})" if class_name and seen else ""
            return self.fail(FailureReason.NO_DETECTION.value, f"no {wanted} among {len(objects)} object(s){classes}")
        found, passed_over = self._failed_last(found)
        order = self.ports.require("order", str)
        point = self.ports.require("point", Pose)
        chosen = found[0]
        if order in ("nearest", "farthest"):
            dist = [math.hypot(d.centroid_base_m[0] - point.x_m, d.centroid_base_m[1] - point.y_m) for d in found]
            chosen = found[int(np.argmin(dist) if order == "nearest" else np.argmax(dist))]
        elif order in ("largest", "smallest"):
            area = [footprint_m2(d) for d in found]
            chosen = found[int(np.argmax(area) if order == "largest" else np.argmin(area))]
        self.ports.set("object", chosen)
        c = chosen.centroid_base_m
        named = f"{class_of(chosen)} " if class_of(chosen) else ""
        later = f" ({passed_over} failed before: later)" if passed_over else ""
        self.feedback_message = (f"{named}{chosen.label} {shape_class_of(chosen)} {chosen.shape} at "
                                 f"({c[0]:.3f}, {c[1]:.3f}) of {len(found)} match(es){later}")
        return Status.SUCCESS


def check_detector_classes(nodes: Iterable[BtNode]) -> None:
    """A literal ``class`` of a SelectObject must be a class of the learned models the tree's perceiving leaves
    name literally (loaded with the tree): :class:`TreeFileError` at the SelectObject's line, with the closest
    class name. Not checked when a perceiving leaf names its detector or model on the blackboard (known only
    when it runs); a tree whose perceiving leaves all use the geometric detector has no classes at all."""
    nodes = list(nodes)
    perceivers = [n for n in nodes if isinstance(n, DetectorLeaf)]
    if not perceivers or any(n.literal_model is None and _detector_unknown(n) for n in perceivers):
        return
    models = {n.literal_model.path: n.literal_model for n in perceivers if n.literal_model is not None}
    for node in nodes:
        if not isinstance(node, SelectObject) or node.ports.key("class") is not None:
            continue
        wanted = _wanted(str(node.ports.get("class")))
        if not wanted or any(wanted in m.names for m in models.values()):
            continue
        ctx = node.ctx
        if not models:
            problem = (f"class '{wanted}' asked, but every perceiving leaf of the tree uses the geometric "
                       f"detector, which names no classes (give PerceiveAll detector=\"learned\")")
        else:
            # deferred: OpenCV comes with it; a tree loads and validates without it
            from bt_grasp.detector.model import ModelError

            try:
                next(iter(models.values())).class_id(wanted)
                problem = ""
            except ModelError as exc:
                problem = exc.problem
        raise TreeFileError(ctx.source or "tree", f"{node.name}: port 'class': {problem}", where=ctx.line or None)


def _detector_unknown(node: DetectorLeaf) -> bool:
    """The leaf's detector is named on the blackboard, or is learned with a model named there."""
    if node.ports.key("detector") is not None:
        return True
    return parse_detector(str(node.ports.get("detector"))) is DetectorKind.LEARNED


@action(
    ports=[
        input_port("object", object, "{object}", "a perceived object"),
        input_port("at", str, "center", "center, top (its top face) or bottom", choices=("center", "top", "bottom")),
        input_port("offset_z", float, 0.0, "added to the height, m (e.g. 0.1: above it)"),
        output_port("pose", object, "the pose (base frame; yaw = the object's)", default="{pose}"),
    ],
    reasons=(FailureReason.BAD_INPUT,),
)
class ObjectPose(Leaf):
    """A perceived object's pose in the base frame: its centre, top face or bottom, raised by ``offset_z``.
    ``at="top"`` is where another object's bottom would rest on it (the z ``Place`` expects).
    FAILURE: BAD_INPUT (``object`` is not a perceived object)."""

    def update(self) -> Status:
        det: object = self.ports.get("object")
        if not is_detection(det):
            return self.fail(FailureReason.BAD_INPUT.value, "'object' is not a perceived object: run SelectObject")
        x, y, z = (float(v) for v in det.centroid_base_m)
        half = float(det.size_m[2]) / 2
        z += {"center": 0.0, "top": half, "bottom": -half}[self.ports.require("at", str)]
        pose = Pose(x, y, z + self.ports.require("offset_z", float), math.degrees(float(det.yaw_rad)))
        self.ports.set("pose", pose)
        self.feedback_message = f"{det.label}: {pose}"
        return Status.SUCCESS


@action(
    ports=[
        input_port("object", object, "{object}", "a perceived object"),
        output_port("color", object, "its colour name ('object' if none)", default="{object_color}"),
        output_port("shape", object, "box or round", default="{object_shape}"),
        output_port("shape_class", object, "box-like, cylinder-like, elongated, flat or other",
                    default="{object_shape_class}"),
        output_port("size", object, "its footprint's long side, m", default="{object_size}"),
        output_port("height", object, "its height, m", default="{object_height}"),
    ],
    reasons=(FailureReason.BAD_INPUT,),
)
class ObjectInfo(Leaf):
    """A perceived object's colour, shape, shape class and size as plain values (for Switch, scripts, ports).
    FAILURE: BAD_INPUT (``object`` is not a perceived object)."""

    def update(self) -> Status:
        det: object = self.ports.get("object")
        if not is_detection(det):
            return self.fail(FailureReason.BAD_INPUT.value, "'object' is not a perceived object: run SelectObject")
        self.ports.set("color", str(det.label))
        self.ports.set("shape", str(det.shape))
        self.ports.set("shape_class", shape_class_of(det))
        self.ports.set("size", float(max(det.size_m[0], det.size_m[1])))
        self.ports.set("height", float(det.size_m[2]))
        self.feedback_message = f"{det.label} {shape_class_of(det)} {det.shape}"
        return Status.SUCCESS


@condition(
    ports=[
        _OBJECTS_IN,
        input_port("color", str, "", "count only objects of this colour (empty: all)"),
        input_port("min", int, 1, "SUCCESS needs at least this many"),
        input_port("max", int, -1, "... and at most this many (-1: no limit)"),
        output_port("count", object, "how many were counted", default="{object_count}"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.NO_DETECTION, FailureReason.COUNT_EXCEEDED),
)
class ObjectCount(Leaf):
    """Count the objects of a list (optionally of one colour); SUCCESS when min <= count <= max.
    FAILURE: NO_DETECTION (fewer than ``min``), COUNT_EXCEEDED (more than ``max``), BAD_INPUT."""

    def update(self) -> Status:
        objects = object_list(self.ports.get("objects"))
        if objects is None:
            return self.fail(FailureReason.BAD_INPUT.value, "'objects' is not an object list: run PerceiveAll first")
        color = self.ports.require("color", str)
        count = sum(1 for d in objects if not color or d.label == color)
        self.ports.set("count", count)
        low, high = self.ports.require("min", int), self.ports.require("max", int)
        what = f"{color} object(s)" if color else "object(s)"
        if count < low:
            return self.fail(FailureReason.NO_DETECTION.value, f"{count} {what}, fewer than {low}")
        if 0 <= high < count:
            return self.fail(FailureReason.COUNT_EXCEEDED.value, f"{count} {what}, more than {high}")
        self.feedback_message = f"{count} {what}"
        return Status.SUCCESS


@action(
    ports=[
        input_port("fixture", str, description="a fixture's name in the scene file", required=True),
        input_port("slot", int, -1, "a tray's or bin's slot, row by row from 0 (-1: centre)"),
        input_port("slot_size", float, 0.10, "the side of one square slot, m"),
        output_port("pose", object, "its centre on its surface (base frame)", default="{pose}"),
    ],
    reasons=(FailureReason.BAD_INPUT,),
    needs_robot=True,
)
class FixturePose(RobotLeaf):
    """Where a fixture (tray, bin, marker, wall) is, from the scene file (installation data, not
    perception): its centre in x, y, its yaw, and z = the surface an object set on it rests on (a tray's
    floor). With ``slot`` >= 0, the centre of that square slot of a tray or bin (slots of ``slot_size`` in
    rows along the container's x, so several objects set down in it do not land on each other). An unknown
    name in a tree file is a load error. FAILURE: BAD_INPUT (unknown name from the blackboard, a slot
    beyond the container's or a slot of something that is not a container)."""

    def check_scene(self, scene: Scene) -> str | None:
        """A problem with the literal ``fixture`` port for this scene (checked before the run), or None."""
        if self.ports.key("fixture") is not None:
            return None
        return _fixture_problem(scene, self.ports.require("fixture", str))

    def update(self) -> Status:
        name = self.ports.require("fixture", str)
        pose = fixture_pose(self.cell.scene, name, self.ports.require("slot", int),
                            self.ports.require("slot_size", float))
        if isinstance(pose, str):
            return self.fail(FailureReason.BAD_INPUT, pose)
        self.ports.set("pose", pose)
        fixture = self.cell.scene.fixture(name)
        self.feedback_message = f"{fixture.kind if fixture is not None else 'fixture'} {name}: {pose}"
        return Status.SUCCESS


def fixture_pose(scene: Scene, name: str, slot: int = -1, slot_size_m: float = 0.10) -> Pose | str:
    """FixturePose's answer: the centre of fixture ``name`` (or of its square ``slot``) on its surface, in the
    base frame; or why there is none (one sentence). Shared with the dry run's stand-in (``--scene``)."""
    fixture = scene.fixture(name)
    if fixture is None:
        return str(_fixture_problem(scene, name))
    offset = _slot_offset(fixture, slot, slot_size_m)
    if isinstance(offset, str):
        return offset
    yaw = math.radians(float(fixture.yaw_deg))
    x = fixture.center_xy_m[0] + math.cos(yaw) * offset[0] - math.sin(yaw) * offset[1]
    y = fixture.center_xy_m[1] + math.sin(yaw) * offset[0] + math.cos(yaw) * offset[1]
    world = Pose(x, y, float(fixture.surface_z_m), float(fixture.yaw_deg), "world")
    return world.in_base(scene.T_world_base())


def _slot_offset(fixture: Fixture, slot: int, size_m: float) -> tuple[float, float] | str:
    """A slot's centre relative to the container's centre (its own axes), or why there is no such slot."""
    if slot < 0:
        return (0.0, 0.0)
    inner = getattr(fixture, "inner_size_m", None)
    if inner is None:
        return f"'{fixture.name}' is a {fixture.kind}, which has no slots (only trays and bins do)"
    if size_m <= 0:
        return f"slot_size must be positive, got {size_m}"
    cols, rows = int(inner[0] // size_m), int(inner[1] // size_m)
    if slot >= cols * rows:
        return f"'{fixture.name}' has {cols * rows} slot(s) of {size_m * 100:.0f} cm; slot {slot} does not exist"
    col, row = slot % cols, slot // cols
    return ((col - (cols - 1) / 2) * size_m, (row - (rows - 1) / 2) * size_m)


def _fixture_problem(scene: Scene, name: str) -> str | None:
    if scene.fixture(name) is not None:
        return None
    names = [f.name for f in scene.fixtures]
    return f"no fixture named '{name}' in the scene (fixtures: {', '.join(names) or 'none'}){did_you_mean(name, names)}"
