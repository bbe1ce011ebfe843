"""The twin's parts without the simulator: RTDE packing and the output table, the recognition of ur_rtde's
control script (taken from the installed wheel by its own ScriptClient), the motion profiles and rotations, the
Robotiq register logic on a stand-in finger drive, and the ports' refusals (oversized or unfinished messages)."""

from __future__ import annotations

import logging
import math
import re
import socket
import struct
import time

import numpy as np
import pytest

from bt_grasp.bench.twin_process import free_loopback
from bt_grasp.cell.grippers import ROBOTIQ_2F85
from bt_grasp.sim.twin.control_script import UR_RTDE_1_6_5_CB3, ControlScript, fingerprint, recognise
from bt_grasp.sim.twin.motion import Decelerate, JointMove, Profile, T_to_pose, pose_to_T, rotation_vector
from bt_grasp.sim.twin.netio import IoLoop, Protocol
from bt_grasp.sim.twin.outputs import GETTERS
from bt_grasp.sim.twin.robotiq import POS_CLOSED, POS_OPEN, Robotiq2F85
from bt_grasp.sim.twin.rtde_server import ControllerVersion, RtdeHub
from bt_grasp.sim.twin.rtde_types import INPUT_FIELDS, OUTPUT_FIELDS, FieldType, Recipe, parse_names
from bt_grasp.sim.twin.state import ControllerState, InputBank, RuntimeState, SafetyMode


# --- RTDE ----------------------------------------------------------------------------------------------------
def test_a_recipe_packs_what_it_unpacks_big_endian() -> None:
    recipe = Recipe(3, ("a", "b", "c", "d"), (FieldType.DOUBLE, FieldType.VECTOR6INT32, FieldType.UINT64,
                                               FieldType.BOOL))
    package = recipe.pack([1.5, (1, -2, 3, 4, 5, 6), 2**40, True])
    assert struct.unpack(">HB", package[:3]) == (len(package), ord("U"))
    assert package[3] == 3 and package[4:12] == struct.pack(">d", 1.5)
    assert recipe.unpack(package[3:]) == (1.5, (1, -2, 3, 4, 5, 6), 2**40, True)
    with pytest.raises(ValueError, match="needs 42 bytes"):
        recipe.unpack(package[3:-1])


def test_every_output_field_has_a_value_and_ur_rtdes_recipes_are_known() -> None:
    assert set(GETTERS) == set(OUTPUT_FIELDS)
    state = ControllerState(runtime_state=RuntimeState.PLAYING, safety_mode=SafetyMode.PROTECTIVE_STOP)
    assert GETTERS["runtime_state"](state) == 2 and GETTERS["safety_status_bits"](state) == 0b100_0000_0100
    assert GETTERS["robot_status_bits"](state) == 0b11  # powered, program running
    # the fields ur_rtde 1.6.5's receive and io interfaces ask a 3.15 controller for (taken from the wheel)
    for name in ("actual_TCP_pose", "joint_mode", "payload_inertia", "output_double_register_19",
                 "actual_digital_output_bits", "target_speed_fraction"):
        assert name in OUTPUT_FIELDS
    for name in ("speed_slider_mask", "standard_digital_output", "input_int_register_23", "external_force_torque"):
        assert name in INPUT_FIELDS


def test_setup_names_are_ascii_and_a_trailing_comma_is_ignored() -> None:
    assert parse_names(b"timestamp,actual_q,") == ["timestamp", "actual_q"]
    with pytest.raises(ValueError, match="control characters"):
        parse_names(b"time\x00stamp")


def test_input_claims_are_per_connection() -> None:
    hub = RtdeHub(ControllerVersion(3, 15, 7, 1), 125.0, InputBank())
    first, second = object(), object()
    assert hub.claim(first, ["input_int_register_0"]) == ["INT32"]  # type: ignore[arg-type]
    assert hub.claim(first, ["input_int_register_0", "input_double_register_0"]) == ["INT32", "DOUBLE"]  # type: ignore[arg-type]
    assert hub.claim(second, ["input_int_register_0"]) == ["IN_USE"]  # type: ignore[arg-type]
    assert hub.claim(second, ["nope"]) == ["NOT_FOUND"]  # type: ignore[arg-type]


def test_the_input_bank_applies_a_package_atomically_and_keeps_io_requests_in_order() -> None:
    bank = InputBank()
    bank.write(("input_int_register_0", "input_double_register_5", "speed_slider_mask", "speed_slider_fraction"),
               (11, 0.25, 1, 0.5))
    ints, doubles, _, io = bank.snapshot()
    assert ints[0] == 11 and doubles[5] == 0.25 and io == [("speed_slider_mask", 1), ("speed_slider_fraction", 0.5)]
    assert bank.snapshot()[3] == []
    assert bank.last_update("input_int_register_0") is not None


# --- the control script ----------------------------------------------------------------------------------------
def _uploaded_by_the_wheel() -> str:
    """What ur_rtde 1.6.5's own ScriptClient sends for a 3.15 controller (no register offset injected: only
    RTDEControlInterface injects it)."""
    script_client = pytest.importorskip("script_client")
    host = free_loopback(salt=11)
    with socket.socket() as listener:
        listener.bind((host, 30003))
        listener.listen(1)
        client = script_client.ScriptClient(host, 3, 15)
        client.connect()
        peer, _ = listener.accept()
        assert client.sendScript()
        peer.settimeout(2.0)
        received = b""
        while not received.endswith(b"end\n"):
            received += peer.recv(65536)
        client.disconnect()
        peer.close()
    return received.decode()


@pytest.mark.real_client
def test_the_fingerprint_is_the_installed_wheels_script() -> None:
    text = _uploaded_by_the_wheel()
    assert text.startswith("def rtde_control():\n")
    assert fingerprint(text) == UR_RTDE_1_6_5_CB3
    injected = text.replace("# float register offset\n", "# float register offset\n24").replace(
        "# int register offset\n", "# int register offset\n24")
    found = recognise(injected)
    assert isinstance(found, ControlScript) and found.register_offset == 24 and not found.has_path
    pathed = injected.replace("        # inject move path\n",
                              "        # inject move path\n\tsignal_async_progress(0)\n\tmovej([0,0,0,0,0,0])\n")
    assert isinstance(recognise(pathed), ControlScript) and recognise(pathed).has_path  # type: ignore[union-attr]
    assert "not run" in str(recognise(injected.replace("movej(q, a=acceleration", "movej(q, a=2*acceleration")))
    assert "offsets" in str(recognise(text))  # nothing injected: URScript would not even parse it


# --- motion ----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("distance", "speed", "accel"), [(1.0, 1.0, 2.0), (0.1, 1.0, 2.0), (0.0, 1.0, 1.0)])
def test_a_trapezoid_ends_where_it_should_and_respects_its_limits(distance: float, speed: float, accel: float) -> None:
    profile = Profile(distance, speed, accel)
    ts = np.linspace(0, profile.duration_s, 400)
    samples = np.array([profile.sample(t) for t in ts])
    assert samples[-1, 0] == pytest.approx(distance) and samples[-1, 1] == pytest.approx(0.0, abs=1e-12)
    assert samples[:, 1].max() <= speed + 1e-9
    assert np.all(np.diff(samples[:, 0]) >= -1e-12)
    if distance:
        assert np.max(np.abs(np.diff(samples[:, 1]) / np.diff(ts))) <= accel * 1.01


def test_movej_synchronises_the_joints_and_a_stop_decelerates_to_rest() -> None:
    move = JointMove(np.zeros(6), np.array([1.0, 0.5, 0, 0, 0, -0.25]), 1.0, 4.0)
    q = qd = np.zeros(6)
    while not move.done:
        q, qd = move.advance(0.002)
        assert np.allclose(qd / max(abs(qd[0]), 1e-12) * abs(qd[0]), qd)  # all joints along one direction
    assert np.allclose(q, [1.0, 0.5, 0, 0, 0, -0.25]) and not qd.any()
    stop = Decelerate.joint(np.zeros(6), np.array([2.0, -1.0, 0, 0, 0, 0]), 4.0)
    assert stop.duration == pytest.approx(0.5)
    while not stop.done:
        q, qd = stop.advance(0.002)
    assert q[0] == pytest.approx(0.5) and q[1] == pytest.approx(-0.25) and not qd.any()  # v^2 / (2 a)


@pytest.mark.parametrize("rv", [[0.0, 0.0, 0.0], [0.3, -0.2, 1.1], [math.pi, 0, 0], [0, math.pi - 1e-8, 0],
                                [2.2, 2.2, 0.0]])
def test_rotation_vectors_go_round_trip(rv: list[float]) -> None:
    pose = np.array([0.1, -0.2, 0.3, *rv])
    back = T_to_pose(pose_to_T(pose))
    assert np.allclose(pose_to_T(back), pose_to_T(pose), atol=1e-9)
    assert float(np.linalg.norm(rotation_vector(pose_to_T(pose)[:3, :3]))) <= math.pi + 1e-9


# --- the Robotiq register logic --------------------------------------------------------------------------------
class FingerStandIn:
    """Fingers that move at the commanded speed and stop at an object ``block_m`` wide."""

    def __init__(self, block_m: float = 0.0) -> None:
        self.width = 0.085
        self.block = block_m

    def set_opening_target(self, width_m: float, force_n: float) -> None:
        self.width = min(0.085, max(width_m, self.block, 0.0))

    def opening_m(self) -> float:
        return self.width


def _settle(device: Robotiq2F85, cycles: int = 400) -> None:
    for _ in range(cycles):
        device.step(0.008)
        if device.obj:
            return


def test_the_device_activates_moves_and_detects_an_object() -> None:
    fingers = FingerStandIn(block_m=0.05)
    device = Robotiq2F85(ROBOTIQ_2F85, fingers)
    device.set([("POS", 255), ("GTO", 1)])  # before activation: nothing moves
    _settle(device, 10)
    assert device.get("STA") == 0 and fingers.width == 0.085
    device.set([("ACT", 1)])
    assert device.get("STA") == 1
    _settle(device, 70)
    assert device.get("STA") == 3
    device.set([("POS", 255), ("SPE", 255), ("FOR", 100), ("GTO", 1)])
    assert device.get("PRE") == 255 and device.get("OBJ") == 0
    _settle(device)
    assert device.get("OBJ") == 2 and fingers.width == pytest.approx(0.05)  # stopped on it while closing
    assert device.counts_to_opening_m(POS_OPEN) == 0.085 and device.counts_to_opening_m(POS_CLOSED) == 0.0
    device.set([("POS", 0), ("GTO", 1)])
    _settle(device)
    assert device.get("OBJ") == 3 and device.get("POS") == POS_OPEN
    device.set([("ACT", 0)])
    assert device.get("STA") == 0 and device.get("GTO") == 0


# --- the ports' bounds -----------------------------------------------------------------------------------------
def test_an_oversized_or_unfinished_rtde_package_is_refused_in_one_sentence(caplog: pytest.LogCaptureFixture) -> None:
    host = free_loopback(salt=23)
    hub = RtdeHub(ControllerVersion(3, 15, 7, 1), 125.0, InputBank())
    loop = IoLoop(host, [Protocol("RTDE", 30004, hub.make_session, 4, message_timeout_s=0.3)])
    loop.bind()
    loop.start()
    caplog.set_level(logging.WARNING)
    try:
        with socket.create_connection((host, 30004), timeout=2) as s:
            s.sendall(struct.pack(">HB", 60000, ord("I")))
            assert s.recv(100) == b""  # closed
        with socket.create_connection((host, 30004), timeout=2) as s:
            s.sendall(struct.pack(">HB", 20, ord("I")) + b"abc")  # 17 bytes promised, 3 sent
            start = time.monotonic()
            assert s.recv(100) == b""
            assert 0.25 < time.monotonic() - start < 2.0
    finally:
        loop.stop()
    messages = [r.getMessage() for r in caplog.records]
    assert any("an RTDE package of 60000 bytes (type 73); the twin takes 3 to 8192 bytes" in m for m in messages)
    assert any("was not finished (the twin waits 0.3 s)" in m for m in messages)


# --- the control port's requests -------------------------------------------------------------------------------
class TwinStandIn:
    def __init__(self) -> None:
        self.calls: list[tuple[str, object]] = []

    def status(self) -> dict[str, object]:
        return {"robot_mode": "RUNNING"}

    def inject(self, fault: object, seconds: float | None) -> str:
        self.calls.append(("inject", (fault, seconds)))
        return "done"

    def judge(self, goal_json: str | None) -> dict[str, object]:
        self.calls.append(("judge", goal_json))
        return {"success": False}

    def camera(self, action: str, rate_hz: float | None) -> dict[str, object]:
        self.calls.append(("camera", (action, rate_hz)))
        return {}


@pytest.mark.parametrize(("line", "error"), [
    ("", "an empty request"), ("reboot", "unknown request 'reboot'"), ("fault fire", "unknown fault 'fire'"),
    ("fault drop-connections 9999", "0 to 600 seconds"), ("fault pendant-stop now", "takes no argument"),
    ("camera on 1000", "0.1 to 60 Hz"), ("camera sideways", "camera takes on [HZ], off or capture"),
])
def test_the_control_port_refuses_a_bad_request_in_one_sentence(line: str, error: str) -> None:
    from bt_grasp.sim.twin.control_port import ControlSession, RequestError

    session = ControlSession(None, TwinStandIn())  # type: ignore[arg-type]
    with pytest.raises(RequestError, match=re.escape(error)):
        session._handle(line)


def test_the_control_port_passes_good_requests_on() -> None:
    from bt_grasp.sim.twin.control_port import ControlSession
    from bt_grasp.sim.twin.faults import TwinFault

    twin = TwinStandIn()
    session = ControlSession(None, twin)  # type: ignore[arg-type]
    assert session._handle("fault drop-connections 2.5") == {"fault": "drop-connections", "done": "done"}
    assert session._handle('judge {"kind": "clear"}') == {"success": False}
    assert session._handle("camera on 12") == {}
    assert twin.calls == [("inject", (TwinFault.DROP_CONNECTIONS, 2.5)), ("judge", '{"kind": "clear"}'),
                          ("camera", ("on", 12.0))]


# --- the control script's handshake, on a stand-in arm ---------------------------------------------------------
class ArmStandIn:
    """Moves finish when told to; records what the program asked."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.moving = Handle()

    def movej(self, q: object, accel: float, speed: float) -> Handle:
        self.calls.append(f"movej a={accel} v={speed}")
        self.moving = Handle()
        return self.moving

    def stopj(self, decel: float) -> Handle:
        self.calls.append(f"stopj {decel}")
        return Handle(done=True)

    def set_tcp(self, pose: object) -> None:
        self.calls.append("set_tcp")


class Handle:
    def __init__(self, done: bool = False) -> None:
        self.done = done


def test_the_script_handshake_ready_process_done_clear() -> None:
    from bt_grasp.sim.twin.script_program import ControlProgram, ProgramEnd

    arm = ArmStandIn()
    out_int, out_double = [0] * 48, [0.0] * 48
    program = ControlProgram(arm, 0, out_int, out_double)  # type: ignore[arg-type]
    assert out_int[0] == 1 and out_int[2] == 1 * 65536  # ready; async progress: finished (count 1, op 0)
    ints, doubles = [0] * 48, [0.0] * 48
    ints[0], ints[1], doubles[6], doubles[7] = 1, 0, 1.05, 1.4  # movej, synchronous
    program.step(ints, doubles)
    assert arm.calls == ["movej a=1.4 v=1.05"] and out_int[0] == 1  # blocked inside movej: not done yet
    program.step(ints, doubles)
    assert out_int[0] == 1
    arm.moving.done = True
    program.step(ints, doubles)
    assert out_int[0] == 2  # done
    program.step(ints, doubles)
    assert arm.calls == ["movej a=1.4 v=1.05"]  # the same command is not run twice
    ints[0] = 0  # the client clears the register
    program.step(ints, doubles)
    assert out_int[0] == 1
    ints[0], ints[1] = 1, 1  # asynchronous: done at once, progress "running" with a new operation id
    program.step(ints, doubles)
    assert out_int[0] == 2 and out_int[2] & 32768 and out_int[2] >> 24 == 1
    arm.moving.done = True
    ints[0] = 0
    program.step(ints, doubles)
    assert not out_int[2] & 32768  # the operation finished
    ints[0] = 6  # force mode: a real-time code the twin does not run
    with pytest.raises(ProgramEnd, match="unsupported by the twin: 6"):
        program.step(ints, doubles)


@pytest.mark.parametrize(("code", "register", "what"), [(9, 0, "speedj's joint speeds"), (29, 2, "set_tcp's pose"),
                                                        (34, 0, "stopj's deceleration"),
                                                        (1, 6, "must be positive numbers")])
def test_a_register_holding_nan_stops_the_program_not_the_controller(code: int, register: int, what: str) -> None:
    from bt_grasp.sim.twin.arm import TwinArm
    from bt_grasp.sim.twin.kinematics import UrKinematics
    from bt_grasp.sim.twin.script_program import ControlProgram, ProgramEnd

    q0 = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])
    arm = TwinArm(UrKinematics(), q0, np.eye(4), lambda: (q0, np.zeros(6)), lambda _: None, lambda *_: None)
    program = ControlProgram(arm, 0, [0] * 48, [0.0] * 48)
    ints, doubles = [0] * 48, [0.0] * 48
    ints[0] = code
    doubles[:8] = [*q0, 1.0, 1.0]
    doubles[register] = float("nan")
    with pytest.raises(ProgramEnd, match=re.escape(what)):
        program.step(ints, doubles)
    assert np.all(np.isfinite(arm.advance(0.002, 1.0)[0]))
