"""The robot leaves as node types of a registry."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from bt_grasp.behaviours import (
    calibration_leaves,
    follow,
    gripper,
    motion_leaves,
    objects,
    perceive,
    place,
    viewing,
)
from bt_grasp.errors import TreeFileError
from bt_grasp.perception.results import Detection
from bt_grasp.scene.format import Scene
from bt_grasp.tree.builtins.loops import loop_spec
from bt_grasp.tree.leaf import Leaf
from bt_grasp.tree.node import BtNode
from bt_grasp.tree.registry import NodeRegistry, builtin_registry

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
    place.MoveTo,
    viewing.LookAt,
    follow.FollowTarget,
)


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
    the node's file:line before anything runs. A leaf says how with ``check_scene(scene) -> str | None``."""
    for node in nodes:
        check = getattr(node, "check_scene", None)
        problem = check(scene) if check is not None else None
        if problem and isinstance(node, Leaf):
            ctx = node.ctx
            raise TreeFileError(ctx.source or "tree", f"{node.name}: {problem}", where=ctx.line or None)
