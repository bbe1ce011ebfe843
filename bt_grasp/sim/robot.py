"""The simulated UR5 + gripper: PD joint drives with gravity compensation, a force-bounded gripper."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.robot_description import (
    ARM_JOINTS,
    FINGER_JOINT,
    GRIPPER_LINKS,
    MAX_OPENING_M,
    MIMIC_FINGER_JOINT,
    arm_joint_limits,
    robot_urdf_path,
)
from bt_grasp.scene.format import RobotMount
from bt_grasp.sim.poses import to_pose

ARM_STIFFNESS = 1e4
ARM_DAMPING = 1e3
FINGER_STIFFNESS = 4000.0  # N/m: with the target at fully closed, the force limit bounds the grip
FINGER_DAMPING = 150.0
FINGER_CLOSED_TARGET_M = -0.01  # beyond the joint's closed limit, so the force limit always applies


class SimRobot:
    """Implements :class:`bt_grasp.interfaces.Robot` for the SAPIEN articulation."""

    def __init__(self, scene: sapien.Scene, mount: RobotMount, T_world_base: NDArray[np.float64],
                 urdf_path: Path | None = None) -> None:
        """``urdf_path``: another robot description with the same link names (the twin's gripper models); None:
        bt_grasp's own."""
        loader = scene.create_urdf_loader()
        loader.fix_root_link = True
        for finger in ("left_finger", "right_finger"):
            loader.set_link_material(finger, mount.finger_friction, mount.finger_friction, 0.0)
        self.articulation = loader.load(str(urdf_path or robot_urdf_path()))
        self.articulation.set_name("ur5")
        self.articulation.set_root_pose(to_pose(T_world_base))
        joints = {j.name: j for j in self.articulation.get_active_joints()}
        names = [j.name for j in self.articulation.get_active_joints()]
        self._arm_idx = np.array([names.index(n) for n in ARM_JOINTS])
        self._finger_idx = names.index(FINGER_JOINT)
        self._mimic_idx = names.index(MIMIC_FINGER_JOINT)
        limits = arm_joint_limits()
        self._arm_joints = [joints[n] for n in ARM_JOINTS]
        for joint, effort in zip(self._arm_joints, limits.effort_nm, strict=True):
            joint.set_drive_properties(ARM_STIFFNESS, ARM_DAMPING, effort)
        self._finger = joints[FINGER_JOINT]
        self._finger.set_drive_properties(FINGER_STIFFNESS, FINGER_DAMPING, mount.gripper_force_n)
        joints[MIMIC_FINGER_JOINT].set_drive_properties(0.0, 0.0, 0.0)
        self._default_force_n = mount.gripper_force_n
        self._target_width_m = MAX_OPENING_M
        self.links = {link.name: link for link in self.articulation.get_links()}
        self.gripper_links = tuple(self.links[n] for n in GRIPPER_LINKS)
        self._read: tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.float64]] | None = None
        self.reset(np.asarray(mount.home_q_rad, dtype=float))

    # --- state -------------------------------------------------------------------------------------
    def reset(self, q_rad: NDArray[np.float64], opening_m: float = MAX_OPENING_M) -> None:
        """Place the arm and restore the gripper drive (when building or resetting the world, before time
        starts)."""
        self._finger.set_drive_properties(FINGER_STIFFNESS, FINGER_DAMPING, self._default_force_n)
        qpos = np.zeros(self.articulation.dof)
        qpos[self._arm_idx] = q_rad
        qpos[self._finger_idx] = qpos[self._mimic_idx] = opening_m / 2
        self._read = None
        self.articulation.set_qpos(qpos.astype(np.float32))
        self.articulation.set_qvel(np.zeros(self.articulation.dof, dtype=np.float32))
        self.set_joint_targets(q_rad)
        self._target_width_m = opening_m
        self._finger.set_drive_target(opening_m / 2)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return ARM_JOINTS

    def _state(self) -> tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.float64]]:
        """(qpos as SAPIEN gives it, arm joint positions, arm joint velocities), read once per physics step:
        the executor, the log and the gripper all read the arm in the same tick, and nothing moves it between
        two steps (``before_physics_step`` and ``reset`` forget the reading)."""
        if self._read is None:
            qpos = self.articulation.get_qpos()
            self._read = (qpos, np.asarray(qpos, dtype=float)[self._arm_idx],
                          np.asarray(self.articulation.get_qvel(), dtype=float)[self._arm_idx])
        return self._read

    def joint_positions(self) -> NDArray[np.float64]:
        return self._state()[1].copy()

    def joint_velocities(self) -> NDArray[np.float64]:
        return self._state()[2].copy()

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        q = np.asarray(q_rad, dtype=float)
        targets = q.tolist() if q.shape == (6,) else []  # Python floats: what float() of each element gives
        if not targets or not all(map(math.isfinite, targets)):
            raise ValueError(f"joint targets must be 6 finite numbers, got {q!r}")
        velocities = [0.0] * 6 if qd_rad_s is None else np.asarray(qd_rad_s, dtype=float).tolist()
        for joint, target, velocity in zip(self._arm_joints, targets, velocities, strict=True):
            joint.set_drive_target(target)
            joint.set_drive_velocity_target(velocity)

    def open_gripper(self) -> None:
        self._finger.set_drive_properties(FINGER_STIFFNESS, FINGER_DAMPING, self._default_force_n)
        self._finger.set_drive_target(MAX_OPENING_M / 2)
        self._target_width_m = MAX_OPENING_M

    def close_gripper(self, force_n: float | None = None) -> None:
        force = self._default_force_n if force_n is None else float(force_n)
        self._finger.set_drive_properties(FINGER_STIFFNESS, FINGER_DAMPING, force)
        self._finger.set_drive_target(FINGER_CLOSED_TARGET_M)
        self._target_width_m = 0.0

    def gripper_width_m(self) -> float:
        qpos = self._state()[0]
        return float(qpos[self._finger_idx] + qpos[self._mimic_idx])

    def gripper_target_width_m(self) -> float:
        return self._target_width_m

    # --- physics hook --------------------------------------------------------------------------------
    def before_physics_step(self) -> None:
        """Gravity and Coriolis compensation, as a real UR controller does."""
        self._read = None  # the step about to be taken moves the arm
        qf = self.articulation.compute_passive_force(gravity=True, coriolis_and_centrifugal=True)
        self.articulation.set_qf(qf)
