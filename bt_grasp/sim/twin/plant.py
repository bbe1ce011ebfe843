"""The physical cell the twin's controller drives: the SAPIEN world's arm, fingers and contacts.

:class:`Plant` is what the controller needs (joint states in, drive targets out, one physics step at a time,
collisions); :class:`SapienPlant` gives it from a :class:`bt_grasp.sim.world.World`. The fingers are driven
through the finger joint's drive (position target, force limit), which is what the Robotiq device model moves.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.robot_description import FINGER_JOINT
from bt_grasp.sim.robot import FINGER_DAMPING, FINGER_STIFFNESS
from bt_grasp.sim.world import World

Vec = NDArray[np.float64]
PAD_LINKS = ("left_finger", "right_finger")


class Plant(Protocol):
    @property
    def dt_s(self) -> float: ...

    def joint_state(self) -> tuple[Vec, Vec]:
        """Measured arm joint positions and speeds (rad, rad/s)."""
        ...

    def set_joint_targets(self, q: Vec, qd: Vec) -> None: ...

    def step(self) -> None:
        """One physics step of ``dt_s``."""
        ...

    def collision(self, threshold_n: float) -> str | None:
        """A sentence naming a contact of the arm or gripper pushing harder than ``threshold_n`` in the last step
        (pads on an object do not count: that is a grasp), or None."""
        ...


class SapienPlant:
    """:class:`Plant` and the Robotiq model's ``FingerDrive`` over a SAPIEN :class:`World`."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.robot = world.robot
        joints = {j.name: j for j in self.robot.articulation.get_active_joints()}
        self._finger = joints[FINGER_JOINT]
        self._robot_bodies = {link: link.name for link in self.robot.articulation.get_links()}
        self._pads = {link for link, name in self._robot_bodies.items() if name in PAD_LINKS}
        object_bodies = {}
        for name, entity in world.objects.items():
            body = entity.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
            if body is not None:
                object_bodies[body] = name
        self._objects = object_bodies
        self._finger_force_n = -1.0

    @property
    def dt_s(self) -> float:
        return self.world.dt_s

    def joint_state(self) -> tuple[Vec, Vec]:
        return self.robot.joint_positions(), self.robot.joint_velocities()

    def set_joint_targets(self, q: Vec, qd: Vec) -> None:
        self.robot.set_joint_targets(q, qd)

    def step(self) -> None:
        self.world.step(1)

    def collision(self, threshold_n: float) -> str | None:
        worst, what = 0.0, ""
        for contact in self.world.scene.get_contacts():
            a, b = contact.bodies[0], contact.bodies[1]
            mine, other = (a, b) if a in self._robot_bodies else (b, a)
            if mine not in self._robot_bodies or other in self._robot_bodies:
                continue
            if mine in self._pads and other in self._objects:
                continue  # a grasp
            impulse = float(sum(np.linalg.norm(p.impulse) for p in contact.points))
            force = impulse / self.world.dt_s
            if force > worst:
                other_name = self._objects.get(other) or getattr(getattr(other, "entity", None), "name", "?")
                worst, what = force, f"{self._robot_bodies[mine]} hit {other_name}"
        if worst > threshold_n:
            return f"{what} with {worst:.0f} N (the limit is {threshold_n:.0f} N)"
        return None

    # --- FingerDrive --------------------------------------------------------------------------------------
    def set_opening_target(self, width_m: float, force_n: float) -> None:
        if force_n != self._finger_force_n:
            self._finger.set_drive_properties(FINGER_STIFFNESS, FINGER_DAMPING, force_n)
            self._finger_force_n = force_n
        self._finger.set_drive_target(width_m / 2)

    def opening_m(self) -> float:
        return self.robot.gripper_width_m()
