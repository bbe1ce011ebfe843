"""Grasping is by friction only: joint-space commands close the gripper on a box and lift it.

No planner here: joint targets come from SAPIEN's own IK (this is a test; the product's kinematics live in
bt_grasp.motion) and are interpolated linearly in joint space. The box's true pose comes from the oracle.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sapien

from bt_grasp.robot_description import ARM_JOINTS, TCP_LINK
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.sim.oracle import GroundTruthOracle
from bt_grasp.sim.poses import to_pose
from bt_grasp.sim.world import World

pytestmark = pytest.mark.sim


def _single_box_scene(path: Path) -> Scene:
    base = load_scene(path)
    box = next(o for o in base.objects if o.name == "red_box")
    box = box.model_copy(update={"randomize": box.randomize.model_copy(update={"x_m": (0, 0), "y_m": (0, 0)})})
    return base.model_copy(update={"objects": (box,)})


class JointMover:
    def __init__(self, world: World) -> None:
        self.world = world
        robot = world.robot
        self.model = robot.articulation.create_pinocchio_model()
        names = [j.name for j in robot.articulation.get_active_joints()]
        self.arm = [names.index(n) for n in ARM_JOINTS]
        self.mask = np.zeros(len(names), dtype=np.int32)
        self.mask[self.arm] = 1
        self.tcp = [link.name for link in robot.articulation.get_links()].index(TCP_LINK)

    def ik(self, T_base_tcp: np.ndarray) -> np.ndarray:
        qpos = np.asarray(self.world.robot.articulation.get_qpos(), dtype=float)
        q, ok, _err = self.model.compute_inverse_kinematics(
            self.tcp, to_pose(T_base_tcp), initial_qpos=qpos, active_qmask=self.mask, max_iterations=2000
        )
        assert ok, "test IK failed"
        return np.asarray(q)[self.arm]

    def move(self, q_goal: np.ndarray, duration_s: float) -> None:
        robot, world = self.world.robot, self.world
        q0 = robot.joint_positions()
        ticks = int(duration_s * world.config.physics.control_rate_hz)
        for i in range(1, ticks + 1):
            robot.set_joint_targets(q0 + (q_goal - q0) * i / ticks)
            world.step_tick()
        for _ in range(30):
            world.step_tick()

    def wait(self, seconds: float) -> None:
        for _ in range(int(seconds * self.world.config.physics.control_rate_hz)):
            self.world.step_tick()


def _top_down(T_world_box: np.ndarray, z_m: float) -> np.ndarray:
    yaw_axis = T_world_box[:3, 1]  # close across the box's local x: fingers move along its y axis? no: tcp y
    y = np.array([yaw_axis[0], yaw_axis[1], 0.0])
    y /= np.linalg.norm(y)
    z = np.array([0.0, 0.0, -1.0])
    x = np.cross(y, z)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, y, z], axis=1)
    T[:3, 3] = [T_world_box[0, 3], T_world_box[1, 3], z_m]
    return T


def _pick(world: World, close: bool) -> dict[str, float]:
    oracle = GroundTruthOracle(world)
    mover = JointMover(world)
    world.step(100)
    T_box = oracle.T_world_object("red_box")
    z0 = T_box[2, 3]
    mover.move(mover.ik(_top_down(T_box, z0 + 0.15)), 2.0)
    mover.move(mover.ik(_top_down(T_box, z0 + 0.005)), 1.5)
    if close:
        world.robot.close_gripper()
    mover.wait(0.6)
    width_closed = world.robot.gripper_width_m()
    mover.move(mover.ik(_top_down(T_box, z0 + 0.105)), 1.5)
    T_tcp_box_start = np.linalg.inv(oracle.T_world_tcp()) @ oracle.T_world_object("red_box")
    z_lifted = oracle.T_world_object("red_box")[2, 3]
    mover.wait(2.0)
    T_tcp_box_end = np.linalg.inv(oracle.T_world_tcp()) @ oracle.T_world_object("red_box")
    return {
        "rise_m": z_lifted - z0,
        "rise_after_hold_m": oracle.T_world_object("red_box")[2, 3] - z0,
        "slip_m": float(np.linalg.norm(T_tcp_box_end[:3, 3] - T_tcp_box_start[:3, 3])),
        "width_m": width_closed,
        "held": float(oracle.object_in_gripper("red_box")),
    }


def test_box_is_lifted_by_friction_and_stays(tabletop_scene_path: Path) -> None:
    world = World(_single_box_scene(tabletop_scene_path), seed=3)
    result = _pick(world, close=True)
    assert 0.045 < result["width_m"] < 0.052, result  # the pads stop on the 50 mm box
    assert result["rise_m"] > 0.09, result
    assert result["rise_after_hold_m"] > 0.09, result
    assert result["slip_m"] < 0.002, result
    assert result["held"] == 1.0, result


def test_open_gripper_leaves_box_on_table(tabletop_scene_path: Path) -> None:
    world = World(_single_box_scene(tabletop_scene_path), seed=3)
    result = _pick(world, close=False)
    assert abs(result["rise_after_hold_m"]) < 0.005, result
    assert result["held"] == 0.0, result


def test_no_product_code_moves_objects_by_hand(repo_root: Path) -> None:
    """No welding, attaching or teleporting: objects' poses are never set after the world is built."""
    forbidden = (
        "set_pose(",
        "set_linear_velocity",
        "set_angular_velocity",
        "create_drive",
        "create_connection",
        "create_gear",
        "set_kinematic_target",
        "add_force",
        "set_qpos(",
    )
    offenders = []
    for path in (repo_root / "bt_grasp").rglob("*.py"):
        text = path.read_text()
        for token in forbidden:
            if token in text:
                offenders.append(f"{path.relative_to(repo_root)}: {token}")
    allowed = {
        "bt_grasp/sim/robot.py: set_qpos(",  # placing the arm when the world is built, before time starts
        "bt_grasp/sim/camera.py: set_pose(",  # placing the camera body (no object)
        "bt_grasp/sim/charuco.py: set_pose(",  # placing the calibration board's render body (no physics)
        "bt_grasp/sim/disturbances.py: set_linear_velocity",  # the object_nudge fault: a push; friction stops it
        # the conveyor's slats (the belt, never an object): kinematic targets carry objects by friction, and
        # the slat leaving the downstream end goes back under the upstream one with nothing on it
        "bt_grasp/sim/conveyor.py: set_kinematic_target",
        "bt_grasp/sim/conveyor.py: set_pose(",
        # a mesh/URDF object's entity placed where the scene draws it before it joins the scene (no time has
        # passed; World.settle then lets physics bring it to rest)
        "bt_grasp/sim/objects.py: set_pose(",
        # the twin's render process: a copy of the world that is never stepped, posed each frame as the twin's
        # physics world stands (arm and objects), only to be drawn; nothing in it is simulated
        "bt_grasp/sim/twin/camera_worker.py: set_pose(",
        "bt_grasp/sim/twin/camera_worker.py: set_qpos(",
        # socket.create_connection: a TCP probe of a Ray address, not a physics connection
        "bt_grasp/campaign/ray_engine.py: create_connection",
        # socket.create_connection: a real cell's TCP clients (the gripper's URCap, a twin's camera and control
        # ports), not physics connections
        "bt_grasp/hardware/robotiq_client.py: create_connection",
        "bt_grasp/hardware/twin_camera.py: create_connection",
        "bt_grasp/hardware/twin_control.py: create_connection",
    }
    assert sorted(set(offenders) - allowed) == []
    _ = sapien  # the test module needs sapien installed
