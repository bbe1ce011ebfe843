"""Each injector against stand-ins: the fault arms on its trigger and acts only through the interfaces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_grasp.errors import InputError
from bt_grasp.faults.calibration import OffsetCalibration
from bt_grasp.faults.injector import Injector, install_faults
from bt_grasp.faults.plan import load_fault_plan
from bt_grasp.motion.kinematics import IKStatus
from bt_grasp.motion.planner import PlanStatus
from bt_grasp.tree.node import BtStatus

from .fakes import FakeCalibration, FakeRecorder, Rig, rig


def install(r: Rig, *inject: str) -> tuple[Injector, FakeRecorder]:
    recorder = FakeRecorder()
    injector = install_faults(load_fault_plan(None, list(inject)), r, recorder)
    injector.before_run()
    return injector, recorder


def test_interfaces_are_wrapped_and_pass_through_when_idle() -> None:
    r = rig()
    injector, recorder = install(r, "frame_drop@Perceive#5")
    assert r.cell.camera is not r.camera and r.cell.robot is not r.robot
    assert r.cell.camera.capture() is not None
    r.cell.robot.set_joint_targets(np.ones(6))
    assert len(r.robot.targets) == 1
    assert r.cell.planner.checker("scene", 0.0) == "checker"  # other methods: the real ones
    assert r.cell.kinematics.ik(np.eye(4), np.zeros(6)).ok
    assert injector.fired == 0 and recorder.faults == []


def test_frame_drop_on_the_nth_entry_only() -> None:
    # entry 1: frame; entry 2: armed -> capture None (fired, tick 2); entry 3: frame again
    r = rig()
    injector, recorder = install(r, "frame_drop@Perceive#2")
    perceive = r.nodes["Perceive"]
    results = []
    for tick in (1, 2, 3):
        perceive.enter()
        results.append(r.cell.camera.capture())
        injector.after_tick(tick)
    assert [f is None for f in results] == [False, True, False]
    assert perceive.initialised == 3  # the leaf's own initialise still runs
    assert injector.fired == 1
    ((_, tick, fault),) = recorder.faults
    assert tick == 2 and fault["kind"] == "frame_drop" and fault["leaf"] == "Perceive"
    assert fault["trigger"] == {"on_leaf": "Perceive", "nth": 2}
    assert r.camera.captures == 2  # a dropped frame is never produced


def test_count_limits_the_firings() -> None:
    r = rig()
    injector, recorder = install(r, "frame_drop@Perceive#1:count=2")
    dropped = []
    for tick in range(1, 5):
        r.nodes["Perceive"].enter()
        dropped.append(r.cell.camera.capture() is None)
        injector.after_tick(tick)
    assert dropped == [True, True, False, False]
    assert [t for _, t, _ in recorder.faults] == [1, 2]


def test_depth_hole_blanks_a_rectangle() -> None:
    r = rig()
    injector, _ = install(r, "depth_hole@Perceive:u_px=10,v_px=5,width_px=20,height_px=100")
    r.nodes["Perceive"].enter()
    frame = r.cell.camera.capture()
    assert frame is not None
    assert np.all(frame.depth_m[5:48, 10:30] == 0.0)
    assert np.all(frame.depth_m[:5, 10:30] == np.float32(0.8)) and np.all(frame.depth_m[:, 30:] == np.float32(0.8))
    assert injector.firings[0]["details"]["hole_px"] == [10, 5, 20, 43]  # clipped to the image
    later = r.cell.camera.capture()
    assert later is not None and np.all(later.depth_m[:, 4:] == np.float32(0.8))


def test_depth_burst_is_heavy_seeded_and_keeps_invalid_pixels() -> None:
    def burst(seed: int) -> np.ndarray:
        r = rig(seed=seed)
        install(r, "depth_burst@Perceive:sigma_m=0.05")
        r.nodes["Perceive"].enter()
        frame = r.cell.camera.capture()
        assert frame is not None
        return frame.depth_m

    a, b, c = burst(1), burst(1), burst(2)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert np.all(a[:, :4] == 0.0)
    assert 0.04 < float(np.std(a[:, 4:])) < 0.06


def test_calibration_offset_applies_and_survives_a_reload() -> None:
    r = rig()
    T = np.eye(4)
    T[:3, 3] = [1.0, 0.0, 0.5]
    r.cell.calibration = FakeCalibration(T)
    injector, recorder = install(r, "calib@tick:2:dy_mm=30,dyaw_deg=90")
    injector.after_tick(1)
    assert r.cell.calibration.T_base_camera is T
    injector.after_tick(2)
    assert isinstance(r.cell.calibration, OffsetCalibration)
    T_new = r.cell.calibration.T_base_camera_at()
    assert np.allclose(T_new[:3, 3], [1.0, 0.03, 0.5])
    assert np.allclose(T_new[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    assert r.cell.calibration.mount == "eye-to-hand"
    r.cell.calibration = FakeCalibration(T)  # LoadCalibration reads the file again
    r.nodes["Perceive"].enter()
    assert np.allclose(r.cell.calibration.T_base_camera_at()[:3, 3], [1.0, 0.03, 0.5])
    assert injector.fired == 1 and recorder.faults[0][1] == 2


def test_ik_fail_for_the_next_calls() -> None:
    r = rig()
    injector, _ = install(r, "ik_fail@PlanGrasp:calls=2")
    kin = r.cell.kinematics
    r.nodes["PlanGrasp"].enter()
    q = np.arange(6.0)
    first, (sols, second), third = kin.ik(np.eye(4), q), kin.ik_solutions(np.eye(4), q), kin.ik(np.eye(4), q)
    assert first.status is IKStatus.UNREACHABLE and np.array_equal(first.q, q)
    assert second.status is IKStatus.UNREACHABLE and sols == []
    assert third.ok
    assert np.array_equal(kin.fk(q), np.eye(4))  # forward kinematics never fails
    assert injector.fired == 1


def test_ik_fail_within_attempt_expires_with_the_leaf() -> None:
    r = rig()
    injector, _ = install(r, "ik_fail@PlanGrasp:calls=100,within_attempt=true")
    kin, node = r.cell.kinematics, r.nodes["PlanGrasp"]
    node.enter()
    node.bt_state = BtStatus.RUNNING
    assert not kin.ik(np.eye(4), np.zeros(6)).ok
    injector.after_tick(1)
    assert not kin.ik(np.eye(4), np.zeros(6)).ok  # still its attempt
    node.bt_state = BtStatus.FAILURE
    injector.after_tick(2)
    assert kin.ik(np.eye(4), np.zeros(6)).ok


def test_planner_fail_returns_the_planners_failure_status() -> None:
    r = rig()
    injector, recorder = install(r, "planner_fail@tick:3:status=timeout")
    planner = r.cell.planner
    assert planner.plan_to_pose(None, None, None, None).ok
    injector.after_tick(3)
    failed = planner.plan_to_joints(None, None, None, None)
    assert failed.status is PlanStatus.TIMEOUT and not failed.ok and "injected" in failed.message
    assert planner.plan_to_pose(None, None, None, None).ok
    assert r.planner.calls == 2
    assert recorder.faults[0][1] == 4  # armed after tick 3, acted during tick 4


def test_controller_stall_holds_the_last_target_for_its_duration() -> None:
    r = rig()
    injector, recorder = install(r, "stall@Approach:duration_s=0.5")
    robot = r.cell.robot
    robot.set_joint_targets(np.zeros(6))
    r.nodes["Approach"].enter()
    robot.set_joint_targets(np.ones(6))
    robot.close_gripper(10.0)  # a stall is the arm's controller only
    r.clock.advance_s(0.4)
    injector.after_tick(1)
    robot.set_joint_targets(np.ones(6))
    r.clock.advance_s(0.2)
    injector.after_tick(2)
    robot.set_joint_targets(2 * np.ones(6))
    assert [t[0] for t in r.robot.targets] == [0.0, 2.0]
    assert r.robot.gripper == ["close 10.0"]
    assert injector.fired == 1 and recorder.faults[0][2]["details"]["effect"] == "arm targets ignored"


def test_leaf_timeout_hangs_robot_and_camera_until_it_ends() -> None:
    r = rig()
    injector, _ = install(r, "timeout@Grasp:duration_s=1")
    r.nodes["Grasp"].enter()
    r.cell.robot.close_gripper(40.0)
    r.cell.robot.set_joint_targets(np.ones(6))
    assert r.cell.camera.capture() is None
    r.clock.advance_s(1.0)
    injector.after_tick(100)
    r.cell.robot.close_gripper(40.0)
    assert r.robot.gripper == ["close 40.0"] and len(r.robot.targets) == 0
    assert r.cell.camera.capture() is not None
    assert injector.fired == 1


def test_gripper_slip_weakens_pads_and_drive_then_recovers() -> None:
    r = rig()
    injector, recorder = install(r, "slip@Lift:friction=0.05,force_n=2,duration_s=1")
    physics = r.physics
    r.nodes["Lift"].enter()
    assert physics.pad_friction == 0.05 and physics.force_limit_n == 2.0
    details = recorder.faults[0][2]["details"]
    assert details["pad_friction_before"] == 1.0 and details["force_limit_before_n"] == 40.0
    r.clock.advance_s(0.5)
    injector.after_tick(1)
    assert physics.pad_friction == 0.05  # not yet: the slip lasts 1 s
    r.clock.advance_s(0.5)
    injector.after_tick(2)
    assert physics.pad_friction == 1.0


def test_object_nudge_pushes_the_target_with_a_friction_sized_impulse() -> None:
    r = rig(color="blue")
    _, recorder = install(r, "nudge@PlanGrasp:dx_m=0.03,dy_m=0.04")
    r.nodes["PlanGrasp"].enter()
    mu = 0.5 * (0.4 + 0.6)
    speed = math.sqrt(2 * mu * 9.81 * 0.05)
    assert np.allclose(r.physics.velocities["blue_box"], [speed * 0.6, speed * 0.8, 0.0])
    assert "red_box" not in r.physics.velocities
    assert recorder.faults[0][2]["details"]["object"] == "blue_box"


@pytest.mark.parametrize("touched", [False, True])
def test_a_push_says_which_object_it_hit_and_whether_the_tree_ever_touched_it(touched: bool) -> None:
    """Issue 43, finding 2: a nudge on an object the fingers never touched in the run says so in the run's result."""
    r = rig(color="blue")
    injector, _ = install(r, "nudge@PlanGrasp:dx_m=0.03")
    r.nodes["PlanGrasp"].enter()
    injector.after_tick(1)
    if touched:
        r.physics.touching.add("blue_box")  # the fingers on it for one tick, after the push
    injector.after_tick(2)
    r.physics.touching.clear()
    injector.after_tick(3)
    (firing,) = injector.report()
    assert (firing.kind, firing.target, firing.target_touched, firing.missed) == ("object_nudge", "blue_box", touched,
                                                                                 not touched)
    assert ("never touched blue_box" in firing.sentence()) is not touched


def test_object_nudge_of_an_unknown_object_is_refused_before_the_run() -> None:
    with pytest.raises(InputError, match="no object 'cup'"):
        install(rig(), "nudge@PlanGrasp:object=cup")


def test_unknown_leaf_is_refused_before_the_run() -> None:
    with pytest.raises(InputError, match="on_leaf 'Percieve' names no leaf") as info:
        install(rig(), "frame_drop@Percieve#1")
    assert info.value.source == "--inject"


def test_leaf_matches_by_path_too() -> None:
    r = rig()
    install(r, "frame_drop@Main/Perceive#1")
    r.nodes["Perceive"].enter()
    assert r.cell.camera.capture() is None


def test_probability_trigger_is_seeded_and_bounded_by_count() -> None:
    def pattern(seed: int) -> list[bool]:
        r = rig(seed=seed)
        injector, _ = install(r, "frame_drop@Perceive~0.5:count=3")
        out = []
        for tick in range(1, 21):
            r.nodes["Perceive"].enter()
            out.append(r.cell.camera.capture() is None)
            injector.after_tick(tick)
        return out

    a = pattern(7)
    assert a == pattern(7)
    assert sum(a) == 3
    assert any(pattern(s) != a for s in (8, 9, 10))


def test_without_a_recorder_firings_are_still_counted() -> None:
    r = rig()
    injector = install_faults(load_fault_plan(None, ["frame_drop@Perceive"]), r, None)
    r.nodes["Perceive"].enter()
    assert r.cell.camera.capture() is None
    assert injector.fired == 1 and injector.firings[0]["tick"] == 1


class _MethodCalibration:
    """A calibration whose camera pose is a method (eye-to-hand: fixed; eye-in-hand: tool pose first)."""

    def __init__(self, mount: str, T: np.ndarray) -> None:
        self.mount, self.T, self.tool_link = mount, T, "tool0"

    def T_base_camera_at(self, T_base_tool: np.ndarray | None = None) -> np.ndarray:
        return self.T if T_base_tool is None else T_base_tool @ self.T


@pytest.mark.parametrize("mount", ["eye-to-hand", "eye-in-hand"])
def test_calibration_offset_of_a_method_pose(mount: str) -> None:
    from bt_grasp.faults.calibration import offset_transform

    offset = OffsetCalibration(_MethodCalibration(mount, np.eye(4)), offset_transform((10.0, 0.0, 0.0), (0, 0, 0)))
    T_tool = np.eye(4)
    T_tool[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # the tool turned 90 degrees about z
    T = offset.T_base_camera_at(T_tool) if mount == "eye-in-hand" else offset.T_base_camera_at()
    expected = [0.0, 0.01, 0.0] if mount == "eye-in-hand" else [0.01, 0.0, 0.0]  # tool x is base y
    assert np.allclose(T[:3, 3], expected)


def test_within_attempt_ends_at_the_next_leaf_entry_in_the_same_tick() -> None:
    # PlanGrasp fails, the recovery's leaf is entered, PlanGrasp is retried: all within one tick
    r = rig()
    install(r, "ik_fail@PlanGrasp:calls=100,within_attempt=true")
    kin, node = r.cell.kinematics, r.nodes["PlanGrasp"]
    node.enter()
    assert not kin.ik(np.eye(4), np.zeros(6)).ok
    node.bt_state = BtStatus.FAILURE
    r.nodes["Perceive"].enter()
    node.enter()
    assert kin.ik(np.eye(4), np.zeros(6)).ok


def test_closing_undoes_a_pending_slip_for_the_next_episode() -> None:
    r = rig()
    injector, _ = install(r, "slip@Lift:friction=0.05,duration_s=5")
    r.nodes["Lift"].enter()
    assert r.physics.pad_friction == 0.05
    injector.close()  # the episode ended before the slip's 5 s were over
    assert r.physics.pad_friction == 1.0
