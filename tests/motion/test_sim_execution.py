"""In the simulator: planned trajectories bring the tcp where planned; a friction grasp survives a lift
and a transfer. The oracle's true box pose places the grasp in this test only."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.geometry import make_T, pose_error
from bt_grasp.motion.cartesian import cartesian_path, offset_along_tool_z, offset_in_base
from bt_grasp.motion.collision import collision_checker
from bt_grasp.motion.executor import ExecStatus, TrajectoryExecutor
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.planner import plan_to_pose
from bt_grasp.motion.planning_scene import Box, Cylinder, PlanningScene
from bt_grasp.motion.trajectory import MotionLimits, Trajectory, time_parametrize

pytestmark = pytest.mark.sim

SLOW = MotionLimits().scaled(0.5)


def _execute(world, trajectory: Trajectory, max_s: float = 30.0) -> TrajectoryExecutor:  # type: ignore[no-untyped-def]
    executor = TrajectoryExecutor(world.robot, trajectory, world.clock)
    executor.start()
    for _ in range(int(max_s * 100)):
        world.step_tick()
        if executor.update() is not ExecStatus.RUNNING:
            break
    assert executor.status is ExecStatus.SUCCEEDED, executor.reason
    return executor


def _scene_from_oracle(world, oracle, grasped: str | None) -> PlanningScene:  # type: ignore[no-untyped-def]
    """Obstacles from the true object poses: a stand-in for perception, in this test only."""
    from bt_grasp.motion.planning_scene import table_box

    shapes = []
    for spec in world.config.objects:
        T = oracle.T_base_object(spec.name)
        shape = (Box.at(spec.name, tuple(spec.size_m), T) if spec.shape == "box"
                 else Cylinder.at(spec.name, spec.size_m[0], spec.size_m[1], T))
        shapes.append(shape)
    obstacles = tuple(s for s in shapes if s.name != grasped)
    allowed = next((s for s in shapes if s.name == grasped), None)
    return PlanningScene(table_box(world.config), obstacles).with_allowed_object(allowed)


def _top_down_grasp(kin: ArmKinematics, T_base_box: np.ndarray, q_now: np.ndarray) -> np.ndarray:
    """Top-down tcp pose at the box centre, closing across a pair of faces, least wrist rotation."""
    best, best_cost = None, np.inf
    for k in range(4):
        y = T_base_box[:3, :3] @ np.array([np.cos(k * np.pi / 2), np.sin(k * np.pi / 2), 0.0])
        z = np.array([0.0, 0.0, -1.0])
        T = make_T(np.column_stack([np.cross(y, z), y, z]), T_base_box[:3, 3])
        result = kin.ik(T, q_now)
        if result.ok and np.linalg.norm(result.q - q_now) < best_cost:
            best, best_cost = T, float(np.linalg.norm(result.q - q_now))
    assert best is not None
    return best


def test_plan_execute_grasp_lift_transfer(kin: ArmKinematics) -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    world = World.from_file("scenes/tabletop.yaml", seed=3)
    oracle = GroundTruthOracle(world)
    robot = world.robot
    T_world_base = world.config.T_world_base()
    world.step(50)

    # 1. plan to a pre-grasp pose 10 cm above the box, execute, compare the true tcp with the plan
    T_grasp = _top_down_grasp(kin, oracle.T_base_object("red_box"), robot.joint_positions())
    T_pre = offset_along_tool_z(T_grasp, -0.10)
    scene = _scene_from_oracle(world, oracle, grasped=None)
    plan = plan_to_pose(robot.joint_positions(), T_pre, scene)
    assert plan.ok, plan.message
    _execute(world, time_parametrize(plan.path))
    dp, dr = pose_error(oracle.T_world_tcp(), T_world_base @ kin.fk(plan.path[-1]))
    assert dp < 0.002 and np.rad2deg(dr) < 0.5, (dp, np.rad2deg(dr))

    # 2. straight descent onto the box (it may touch the fingers), close, wait for the width to settle
    grasp_scene = _scene_from_oracle(world, oracle, grasped="red_box")
    descent = cartesian_path(robot.joint_positions(), T_grasp, grasp_scene)
    assert descent.ok, descent.message
    _execute(world, time_parametrize(descent.path, SLOW, blend=True))
    robot.close_gripper()
    widths = []
    for _ in range(200):
        world.step_tick()
        widths.append(robot.gripper_width_m())
        if len(widths) > 10 and abs(widths[-1] - widths[-10]) < 1e-5:
            break
    assert 0.045 < robot.gripper_width_m() < 0.052  # closed on the 5 cm box
    assert oracle.object_in_gripper("red_box")
    T_tcp_box = np.linalg.inv(oracle.T_world_tcp()) @ oracle.T_world_object("red_box")

    # 3. lift 15 cm, then carry 40 cm sideways; the box follows the tcp
    z0 = oracle.object_height_m("red_box")
    carry_scene = PlanningScene(grasp_scene.table, grasp_scene.obstacles)
    lift = cartesian_path(robot.joint_positions(), offset_in_base(kin.fk(robot.joint_positions()), [0, 0, 0.15]),
                          carry_scene)
    assert lift.ok, lift.message
    _execute(world, time_parametrize(lift.path, SLOW, blend=True))
    assert oracle.object_height_m("red_box") - z0 > 0.145
    assert oracle.object_in_gripper("red_box")

    T_now = kin.fk(robot.joint_positions())
    direction = -np.sign(T_now[1, 3]) or 1.0
    transfer = cartesian_path(robot.joint_positions(), offset_in_base(T_now, [0, 0.4 * direction, 0]),
                              carry_scene)
    assert transfer.ok, transfer.message
    assert collision_checker(carry_scene, 0.0).check_path(transfer.path).ok
    _execute(world, time_parametrize(transfer.path, SLOW, blend=True))
    assert oracle.object_in_gripper("red_box")
    slip = np.linalg.norm((np.linalg.inv(oracle.T_world_tcp()) @ oracle.T_world_object("red_box"))[:3, 3]
                          - T_tcp_box[:3, 3])
    assert slip < 0.005
    assert oracle.object_height_m("red_box") - z0 > 0.145
