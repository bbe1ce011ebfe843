"""The simulator's side of physical faults: push an object, weaken the grip (``bt_grasp.faults.physics``'s
:class:`PhysicsHook`). Nothing here sets a body's pose: a push is a velocity that friction stops, a weak
grip is lower pad friction and finger force, and gravity does the rest."""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import sapien

from bt_grasp.robot_description import FINGER_JOINT
from bt_grasp.sim.world import World

log = logging.getLogger(__name__)

FINGER_LINKS = ("left_finger", "right_finger")


class SimDisturbances:
    """Implements :class:`bt_grasp.faults.physics.PhysicsHook` on a :class:`World`."""

    def __init__(self, world: World) -> None:
        self._world = world
        self._bodies: dict[object, str] | None = None  # each object's dynamic body -> its name

    def object_names(self) -> tuple[str, ...]:
        return tuple(self._world.objects)

    def object_color(self, name: str) -> str | None:
        spec = self._world.config.object_spec(name)
        return spec.color if spec is not None and isinstance(spec.color, str) else None

    def sliding_friction(self, name: str) -> float:
        """The object-on-table contact friction: PhysX's default combination, the average of the two."""
        spec = self._world.config.object_spec(name)
        if spec is None:
            raise KeyError(name)
        return 0.5 * (float(spec.friction) + float(self._world.config.table.friction))

    def set_velocity(self, name: str, velocity_m_s: tuple[float, float, float]) -> None:
        body = self._world.objects[name].find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
        if body is None:
            raise ValueError(f"object '{name}' is not a dynamic body that can be pushed")
        body.wake_up()
        body.set_linear_velocity(list(velocity_m_s))  # a push (an impulse), not a teleport

    def objects_touching_fingers(self) -> frozenset[str]:
        """The objects a finger pad touches now (a contact with a non-zero impulse), from one pass over the
        contacts; reading them changes nothing in the world."""
        world = self._world
        if world.physics_steps == 0:  # no contacts exist before the first physics step
            return frozenset()
        fingers = {world.robot.links[name] for name in FINGER_LINKS}
        if self._bodies is None:
            self._bodies = {}
            for object_name, entity in world.objects.items():
                body = entity.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
                if body is not None:
                    self._bodies[body] = object_name
        touched: set[str] = set()
        for contact in world.scene.get_contacts():
            a, b = contact.bodies[0], contact.bodies[1]
            other = b if a in fingers else a if b in fingers else None
            name = self._bodies.get(other) if other is not None else None
            if name is not None and any(float(np.linalg.norm(p.impulse)) > 0 for p in contact.points):
                touched.add(name)
        return frozenset(touched)

    def weaken_grip(self, friction: float | None, force_n: float | None
                    ) -> tuple[dict[str, float], Callable[[], None]]:
        """Lower the pads' friction and/or the finger drive's force limit; returns what changed and how to
        restore the friction (the force limit comes back with the robot's next gripper command)."""
        robot = self._world.robot
        restores: list[Callable[[], None]] = []
        details: dict[str, float] = {}
        if friction is not None:
            for link_name in FINGER_LINKS:
                for shape in robot.links[link_name].get_collision_shapes():
                    material = shape.physical_material
                    old = (float(material.static_friction), float(material.dynamic_friction))
                    material.set_static_friction(friction)
                    material.set_dynamic_friction(friction)
                    details.setdefault("pad_friction_before", old[0])

                    def restore(material: sapien.physx.PhysxMaterial = material, old: tuple[float, float] = old
                                ) -> None:
                        material.set_static_friction(old[0])
                        material.set_dynamic_friction(old[1])

                    restores.append(restore)
            details["pad_friction"] = friction
        if force_n is not None:
            joint = next(j for j in robot.articulation.get_active_joints() if j.name == FINGER_JOINT)
            details["force_limit_before_n"] = float(joint.force_limit)
            joint.set_drive_properties(float(joint.stiffness), float(joint.damping), float(force_n))
            details["force_limit_n"] = force_n

        def restore_all() -> None:
            for restore in restores:
                restore()

        return details, restore_all
