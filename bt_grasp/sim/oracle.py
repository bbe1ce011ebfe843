"""The ground-truth oracle: the ONLY reader of true object and camera poses.

Perception, calibration, planning and behaviours must never import this module (a test scans for it).
Tests, benchmarks and the run summary's judge use it to score what the pipeline did.
"""

from __future__ import annotations

import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.robot_description import TCP_LINK
from bt_grasp.sim.poses import to_T
from bt_grasp.sim.world import World


class GroundTruthOracle:
    """True poses from the simulator, for scoring only."""

    def __init__(self, world: World) -> None:
        self._world = world

    def object_names(self) -> tuple[str, ...]:
        return tuple(self._world.objects)

    def T_world_object(self, name: str) -> Mat4:
        return to_T(self._world.objects[name].get_pose())

    def T_base_object(self, name: str) -> Mat4:
        return np.linalg.inv(self._world.config.T_world_base()) @ self.T_world_object(name)

    def object_height_m(self, name: str) -> float:
        """Height of the object's centre above the table top."""
        return float(self.T_world_object(name)[2, 3])

    def T_world_camera_cv(self) -> Mat4:
        """The camera's true optical-frame pose in the world frame."""
        return self._world.camera.true_T_world_cv()

    def T_base_camera_cv(self) -> Mat4:
        return np.linalg.inv(self._world.config.T_world_base()) @ self.T_world_camera_cv()

    def T_world_link(self, link_name: str) -> Mat4:
        return to_T(self._world.robot.links[link_name].get_entity_pose())

    def T_world_tcp(self) -> Mat4:
        return self.T_world_link(TCP_LINK)

    def object_in_gripper(self, name: str) -> bool:
        """True when both finger pads touch the object (from the physics contacts)."""
        return len(self.fingers_touching(name)) == 2

    def object_touches_fingers(self, name: str) -> bool:
        """True when either finger pad touches the object."""
        return bool(self.fingers_touching(name))

    def fingers_touching(self, name: str) -> set[str]:
        """Names of the finger links in contact (with a non-zero impulse) with the object."""
        if self._world.physics_steps == 0:
            # no contacts exist before the first physics step
            return set()
        robot = self._world.robot
        left, right = robot.links["left_finger"], robot.links["right_finger"]
        body = self._body(name)
        touching = set()
        for contact in self._world.scene.get_contacts():
            bodies = {contact.bodies[0], contact.bodies[1]}
            if body in bodies:
                for finger in (left, right):
                    if finger in bodies and any(np.linalg.norm(p.impulse) > 0 for p in contact.points):
                        touching.add(finger.name)
        return touching

    def object_velocity(self, name: str) -> NDArray[np.float64]:
        """The object's centre velocity, m/s, world frame."""
        return np.asarray(self._body(name).get_linear_velocity(), dtype=float)

    def _body(self, name: str) -> sapien.physx.PhysxRigidDynamicComponent:
        return self._world.objects[name].find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
