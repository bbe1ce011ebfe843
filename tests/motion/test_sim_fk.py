"""FK agrees with SAPIEN's link poses (the simulator loads the same URDF)."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.robot_description import TCP_LINK

pytestmark = pytest.mark.sim

ARM_LINKS = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
             "wrist_3_link", "tool0", "gripper_palm", TCP_LINK)


def test_fk_matches_sapien_link_poses(kin: ArmKinematics) -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    world = World.from_file("scenes/tabletop.yaml", seed=0)
    oracle = GroundTruthOracle(world)
    T_base_world = np.linalg.inv(world.config.T_world_base())
    articulation = world.robot.articulation
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = rng.uniform(kin.lower_rad, kin.upper_rad).astype(np.float32)
        qpos = np.zeros(articulation.dof, dtype=np.float32)
        qpos[:6] = q
        qpos[6:] = kin.opening_m / 2
        articulation.set_qpos(qpos)
        q64 = np.asarray(q, dtype=float)
        for link in ARM_LINKS:
            T_sim = T_base_world @ oracle.T_world_link(link)
            T_ours = kin.fk_link(q64, link)
            assert np.linalg.norm(T_sim[:3, 3] - T_ours[:3, 3]) < 1e-6, link
            np.testing.assert_allclose(T_sim[:3, :3], T_ours[:3, :3], atol=1e-5, err_msg=link)
