"""Faults that act through the physics of the simulated world: a push on an object, a weakened grip.

The simulator is reached only through :class:`PhysicsHook` (``bt_grasp.sim.disturbances`` implements it);
this module decides what to do (which object, how fast), the hook does it. Nothing moves a body by setting
its pose: the push gives the object an initial sliding velocity and friction stops it; the slip lowers the
pads' friction and/or the finger force and lets gravity do the rest.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Protocol

from bt_grasp.errors import InputError

log = logging.getLogger(__name__)

GRAVITY_M_S2 = 9.81


class PhysicsHook(Protocol):
    """What a physical fault may do to the world (a fault-aware hook of the simulator)."""

    def object_names(self) -> tuple[str, ...]: ...

    def object_color(self, name: str) -> str | None: ...

    def sliding_friction(self, name: str) -> float:
        """The friction coefficient between the object and the table."""
        ...

    def set_velocity(self, name: str, velocity_m_s: tuple[float, float, float]) -> None: ...

    def objects_touching_fingers(self) -> frozenset[str]:
        """The objects a finger pad touches now (read only: nothing in the world changes)."""
        ...

    def weaken_grip(self, friction: float | None, force_n: float | None
                    ) -> tuple[dict[str, float], Callable[[], None]]:
        """Lower pad friction and/or finger force; returns what changed and how to restore the friction."""
        ...


def choose_object(physics: PhysicsHook, name: str | None, color: str | None) -> str:
    """The object to push: the one named (``params.object``), else the first of the scene's objects whose colour is
    the blackboard's ``color`` when the run starts, else the scene's first object. The rule of ``run`` and of a
    campaign's episodes alike (they start with the same blackboard: ``bt_grasp.episode.request.run_blackboard``);
    the run's result says when the object pushed is one the tree never touched."""
    names = physics.object_names()
    if name is not None:
        if name not in names:
            known = ", ".join(names)
            raise InputError("fault plan", f"object_nudge: no object '{name}' in the scene; objects: {known}")
        return name
    if color:
        for candidate in names:
            if physics.object_color(candidate) == color:
                return candidate
    if not names:
        raise InputError("fault plan", "object_nudge: the scene has no objects")
    return names[0]


def push_speed_m_s(distance_m: float, friction: float) -> float:
    """Initial speed after which Coulomb friction stops a sliding body at ``distance_m``: v = sqrt(2 mu g d)."""
    return math.sqrt(2.0 * max(friction, 1e-3) * GRAVITY_M_S2 * distance_m)


def push_object(physics: PhysicsHook, name: str, dx_m: float, dy_m: float) -> dict[str, object]:
    """An impulse on the object along (dx, dy) sized so that table friction stops it about that far away."""
    friction = physics.sliding_friction(name)
    distance = math.hypot(dx_m, dy_m)
    speed = push_speed_m_s(distance, friction)
    velocity = (speed * dx_m / distance, speed * dy_m / distance, 0.0)
    physics.set_velocity(name, velocity)
    log.info("pushed %s at %.2f m/s towards (%.3f, %.3f) m", name, speed, dx_m, dy_m)
    return {"object": name, "velocity_m_s": list(velocity), "friction": friction}
