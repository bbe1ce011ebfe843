"""The robot leaves as node types of a registry."""

from __future__ import annotations

from bt_grasp.behaviours import calibration_leaves, gripper, motion_leaves, perceive
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
)


def register_robot_leaves(registry: NodeRegistry) -> NodeRegistry:
    for cls in ROBOT_LEAVES:
        registry.register(cls.bt_spec)  # type: ignore[attr-defined]
    return registry


def robot_registry() -> NodeRegistry:
    """Every built-in node plus bt_grasp's robot leaves: what tree files may name."""
    return register_robot_leaves(builtin_registry())
