"""The robot leaves as node types of a registry: registered by :func:`register_robot_leaves` exactly as a plugin
registers its nodes (each leaf's declaration, ``@action``/``@condition``, is its manifest: ports, failure
reasons, ``needs_robot``)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from bt_grasp.behaviours import (
    belt,
    calibration_leaves,
    follow,
    gripper,
    intercept,
    motion_leaves,
    objects,
    perceive,
    place,
    place_in,
    regrasp,
    search,
    viewing,
)
from bt_grasp.errors import ConfigError, TreeFileError, did_you_mean
from bt_grasp.perception.results import Detection
from bt_grasp.scene.format import Scene
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.node import BtNode
from bt_grasp.tree.node_api import Leaf, NodeRegistry, loop_node
from bt_grasp.tree.plugins import Installed, load_plugins

#: BT.CPP's LoopNode over an object list (from PerceiveAll): pops each perceived object into ``value``
LoopObjects = loop_node(
    "LoopObjects", Detection,
    description="Pops each perceived object of queue (an object list, e.g. from PerceiveAll) into value "
                "and ticks the child once per object; if_empty once the list is exhausted.",
)

#: every robot leaf bt_grasp ships, in the order of README.md's table
NODES: tuple[type[BtNode], ...] = (
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
    regrasp.GripBlocksPlace,
    regrasp.SetDown,
    regrasp.PlanRegrasp,
    search.FindLost,
    search.AttemptRules,
    place.MoveTo,
    viewing.LookAt,
    follow.FollowTarget,
    belt.BeltWaitPose,
    belt.TrackOnBelt,
    intercept.InterceptPick,
    LoopObjects,
)


def register_robot_leaves(registry: NodeRegistry) -> NodeRegistry:
    """bt_grasp's robot leaves, registered as a plugin's ``register(registry)`` registers its nodes."""
    for node in NODES:
        registry.register(node)
    return registry


def robot_registry(leaves: Sequence[str] = (), installed: Installed = True) -> NodeRegistry:
    """Every built-in node plus bt_grasp's robot leaves, the installed plugins' nodes (entry point group
    ``bt_grasp.leaves``: all of them, none, or those named) and those of each ``--leaves`` file or module: what
    tree files may name. A bad plugin raises :class:`bt_grasp.tree.plugins.PluginError` (exit 2)."""
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


#: the robot leaves' ports that filter perceived objects by a colour name or a learned class
_COLOR_PORTS = {"SelectObject": "color", "ObjectCount": "color", "Perceive": "color", "FollowTarget": "color"}
_CLASS_PORTS = {"SelectObject": "class"}


def scene_notes(nodes: Iterable[BtNode], scene: Scene, scene_path: str) -> list[str]:
    """What a tree looks for that the scene never holds (``tree validate --scene``): a literal colour no object of
    the scene has, a literal class no object of it is. Not errors (a tree may handle "none found"), one sentence
    each with the node's file:line; nothing is said where the scene cannot tell (an object whose colour is not a
    colour name, or whose class is unknown)."""
    # deferred: the detector's dataset module brings OpenCV; a tree validates without it
    from bt_grasp.detector.dataset import object_class

    colours = [o.color if isinstance(o.color, str) else None for o in scene.objects]
    classes: list[str | None] = []
    for o in scene.objects:
        try:
            classes.append(object_class(o.shape, o.mesh, Path(scene_path), o.name))
        except ConfigError:
            classes.append(None)
    notes = []
    for node in nodes:
        if not isinstance(node, Leaf):
            continue
        for table, known, what in ((_COLOR_PORTS, colours, "colour"), (_CLASS_PORTS, classes, "class")):
            port = table.get(node.bt_type)
            if port is None or node.ports.key(port) is not None or None in known:
                continue
            wanted = str(node.ports.get(port) or "").strip()
            names = sorted({k for k in known if k})
            if wanted and wanted != "any" and wanted not in names:
                where = f"{node.ctx.source}:{node.ctx.line}" if node.ctx.line else node.ctx.source
                plural = f"{what}es" if what == "class" else f"{what}s"
                notes.append(f"{where}: {node.bt_type} '{node.bt_path}' looks for the {what} '{wanted}', which no "
                             f"object of {scene_path} has (its objects' {plural}: {', '.join(names) or 'none'})"
                             f"{did_you_mean(wanted, names)}")
    return notes
