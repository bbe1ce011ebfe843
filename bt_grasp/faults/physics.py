"""Faults that act through the physics of the simulated world: a push on an object, a weakened grip.

Nothing here moves a body by setting its pose: the push gives the object an initial sliding velocity
(an impulse) and friction stops it; the slip lowers the finger pads' friction and/or the finger drive's
force limit and lets gravity do the rest. The simulator is reached through the World's public objects
(duck-typed: only ``bt_grasp.sim`` imports sapien).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

from bt_grasp.errors import InputError
from bt_grasp.robot_description import FINGER_JOINT

log = logging.getLogger(__name__)

GRAVITY_M_S2 = 9.81
FINGER_LINKS = ("left_finger", "right_finger")


def _dynamic_body(entity: Any) -> Any:
    for component in entity.get_components():
        if hasattr(component, "wake_up") and hasattr(component, "get_linear_velocity"):
            return component
    raise InputError("fault plan", f"object '{entity.get_name()}' is not a dynamic body that can be pushed")


def choose_object(world: Any, name: str | None, color: str | None) -> str:
    """The object to push: the one named, else the scene's object of the tree's colour, else the first."""
    names = list(world.objects)
    if name is not None:
        if name not in world.objects:
            known = ", ".join(names)
            raise InputError("fault plan", f"object_nudge: no object '{name}' in the scene; objects: {known}")
        return name
    if color:
        for obj in world.config.objects:
            if obj.color == color:
                return str(obj.name)
    if not names:
        raise InputError("fault plan", "object_nudge: the scene has no objects")
    return names[0]


def push_speed_m_s(distance_m: float, friction: float) -> float:
    """Initial speed after which Coulomb friction stops a sliding body at ``distance_m``: v = sqrt(2 mu g d)."""
    return math.sqrt(2.0 * max(friction, 1e-3) * GRAVITY_M_S2 * distance_m)


def push_object(world: Any, name: str, dx_m: float, dy_m: float) -> dict[str, Any]:
    """An impulse on the object along (dx, dy) sized so that table friction stops it about that far away.

    The contact friction is PhysX's default combination (the average of the object's and the table's).
    """
    spec = next(o for o in world.config.objects if o.name == name)
    friction = 0.5 * (float(spec.friction) + float(world.config.table.friction))
    distance = math.hypot(dx_m, dy_m)
    speed = push_speed_m_s(distance, friction)
    velocity = [speed * dx_m / distance, speed * dy_m / distance, 0.0]
    body = _dynamic_body(world.objects[name])
    body.wake_up()
    body.set_linear_velocity(velocity)  # a push (an impulse), not a teleport: friction stops it
    log.info("pushed %s at %.2f m/s towards (%.3f, %.3f) m", name, speed, dx_m, dy_m)
    return {"object": name, "velocity_m_s": velocity, "friction": friction}


def weaken_grip(world: Any, friction: float | None, force_n: float | None) -> tuple[dict[str, Any], Callable[[], None]]:
    """Lower the pad friction and/or the finger drive's force limit; returns what changed and how to
    restore the friction (the force limit is restored by the robot's next gripper command)."""
    restores: list[Callable[[], None]] = []
    details: dict[str, Any] = {}
    if friction is not None:
        for link_name in FINGER_LINKS:
            for shape in world.robot.links[link_name].get_collision_shapes():
                material = shape.physical_material
                old = (material.static_friction, material.dynamic_friction)
                material.set_static_friction(friction)
                material.set_dynamic_friction(friction)
                details.setdefault("pad_friction_before", old[0])

                def restore(material: Any = material, old: tuple[float, float] = old) -> None:
                    material.set_static_friction(old[0])
                    material.set_dynamic_friction(old[1])

                restores.append(restore)
        details["pad_friction"] = friction
    if force_n is not None:
        joint = next(j for j in world.robot.articulation.get_active_joints() if j.name == FINGER_JOINT)
        details["force_limit_before_n"] = float(joint.force_limit)
        joint.set_drive_properties(float(joint.stiffness), float(joint.damping), float(force_n))
        details["force_limit_n"] = force_n

    def restore_all() -> None:
        for restore in restores:
            restore()

    return details, restore_all
