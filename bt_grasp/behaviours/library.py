"""The robot leaves as node types of a registry."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence

from bt_grasp.behaviours import (
    calibration_leaves,
    follow,
    gripper,
    motion_leaves,
    objects,
    perceive,
    place,
    place_in,
    viewing,
)
from bt_grasp.behaviours.reasons import FailureReason as R
from bt_grasp.errors import TreeFileError
from bt_grasp.perception.results import Detection
from bt_grasp.scene.format import Scene
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.builtins.loops import loop_spec
from bt_grasp.tree.leaf import Leaf
from bt_grasp.tree.node import BtNode
from bt_grasp.tree.registry import NodeRegistry

ROBOT_LEAVES = (
    calibration_leaves.LoadCalibration,
    calibration_leaves.Calibrate,
    perceive.Perceive,
    perceive.ObjectVisible,
    motion_leaves.PlanGrasp,
    motion_leaves.Approach,
    motion_leaves.Lift,
    motion_leaves.Retreat,
    motion_leaves.MoveHome,
    motion_leaves.MoveAbove,
    gripper.OpenGripper,
    gripper.Grasp,
    gripper.IsGrasped,
    objects.PerceiveAll,
    objects.SelectObject,
    objects.ObjectPose,
    objects.ObjectCount,
    objects.ObjectInfo,
    objects.FixturePose,
    place.Place,
    place.PlaceOn,
    place_in.PlaceIn,
    place.MoveTo,
    viewing.LookAt,
    follow.FollowTarget,
)

_MOTION = (R.IK_UNREACHABLE, R.COLLISION, R.PLAN_FAILED, R.TRACKING_ERROR)  # a planned, executed motion
_PERCEPTION = (R.CALIBRATION_MISSING, R.NO_FRAME, R.BAD_INPUT, R.NO_DETECTION)  # one capture + detection

#: per robot leaf, the reasons it may fail with (its own ``failed`` calls plus those of the motion or perception
#: job it runs), declared on its spec below (``NodeSpec.failure_reasons``) for those that do not declare them in
#: their ``@leaf(..., reasons=...)``: what a dry run's stand-in fails with (``tree run --dry --outcome/--random``)
DECLARED_REASONS: dict[str, tuple[R, ...]] = {
    "LoadCalibration": (R.CALIBRATION_MISSING,),
    "Calibrate": (R.CALIBRATION_FAILED, R.PLAN_FAILED, R.TRACKING_ERROR),
    "Perceive": _PERCEPTION,
    "ObjectVisible": _PERCEPTION,
    "PerceiveAll": _PERCEPTION,
    "PlanGrasp": (R.NO_DETECTION, R.NOTHING_TO_GRASP, R.IK_UNREACHABLE, R.PLAN_FAILED),
    "Approach": (R.BAD_INPUT, *_MOTION),
    "Lift": (R.BAD_INPUT, R.SLIPPED, *_MOTION),
    "Retreat": _MOTION,
    "MoveHome": _MOTION,
    "MoveAbove": _MOTION,
    "MoveTo": (R.BAD_INPUT, *_MOTION),
    "LookAt": (R.BAD_INPUT, R.CALIBRATION_MISSING, *_MOTION),
    "OpenGripper": (R.TIMEOUT,),
    "Grasp": (R.GRASP_EMPTY, R.TIMEOUT),
    "IsGrasped": (R.GRASP_EMPTY, R.SLIPPED),
    "FixturePose": (R.BAD_INPUT,),
    "Place": (R.BAD_INPUT, R.NOT_HOLDING, R.PLACE_BLOCKED, R.DROPPED, R.TIMEOUT, *_MOTION),
    "PlaceOn": (R.BAD_INPUT, R.NOT_HOLDING, R.PLACE_BLOCKED, R.DROPPED, R.TIMEOUT, *_MOTION),
    "PlaceIn": (R.BAD_INPUT, R.NOT_HOLDING, R.PLACE_BLOCKED, R.DROPPED, R.TIMEOUT, *_MOTION),
    "FollowTarget": (R.BAD_INPUT, R.TARGET_LOST, R.IK_UNREACHABLE),
    "SelectObject": (R.BAD_INPUT, R.NO_DETECTION),
    "ObjectPose": (R.BAD_INPUT,),
    "ObjectInfo": (R.BAD_INPUT,),
    "ObjectCount": (R.BAD_INPUT, R.NO_DETECTION, R.COUNT_EXCEEDED),
}

for _cls in ROBOT_LEAVES:  # each spec carries its reasons (a leaf's own declaration wins)
    _spec = _cls.bt_spec  # type: ignore[attr-defined]
    if not _spec.failure_reasons:
        _cls.bt_spec = dataclasses.replace(  # type: ignore[attr-defined]
            _spec, failure_reasons=tuple(r.value for r in DECLARED_REASONS.get(_spec.name, ())))


#: BT.CPP's LoopNode over an object list (from PerceiveAll): pops each perceived object into ``value``
LOOP_OBJECTS = loop_spec(
    "LoopObjects", Detection,
    description="Pops each perceived object of queue (an object list, e.g. from PerceiveAll) into value "
                "and ticks the child once per object; if_empty once the list is exhausted.",
)


def register_robot_leaves(registry: NodeRegistry) -> NodeRegistry:
    for cls in ROBOT_LEAVES:
        registry.register(cls.bt_spec)  # type: ignore[attr-defined]
    registry.register(LOOP_OBJECTS)
    return registry


def robot_registry(leaves: Sequence[str] = (), installed: bool = True) -> NodeRegistry:
    """Every built-in node plus bt_grasp's robot leaves, the installed plugins' nodes (entry point group
    ``bt_grasp.leaves``, when ``installed``) and those of each ``--leaves`` file or module: what tree files
    may name. A bad plugin raises :class:`bt_grasp.tree.plugins.PluginError` (exit 2)."""
    from bt_grasp.tree.plugins import load_plugins

    return load_plugins(register_robot_leaves(builtin_registry()), leaves, installed)


def check_tree_against_scene(nodes: Iterable[BtNode], scene: Scene) -> None:
    """Literal ports that name scene things (a fixture, a place pose) must fit the scene: TreeFileError with
    the node's file:line before anything runs. A leaf says how with ``check_scene(scene) -> str | None``.
    A SelectObject's literal class must be one of the tree's learned models' (``check_detector_classes``)."""
    nodes = list(nodes)
    objects.check_detector_classes(nodes)
    for node in nodes:
        check = getattr(node, "check_scene", None)
        problem = check(scene) if check is not None else None
        if problem and isinstance(node, Leaf):
            ctx = node.ctx
            raise TreeFileError(ctx.source or "tree", f"{node.name}: {problem}", where=ctx.line or None)
