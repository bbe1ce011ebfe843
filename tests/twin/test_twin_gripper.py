"""The twin's Robotiq socket as ur_rtde's C++ client speaks to it (``robotiq_cpp_replica.py``), and a whole pick
through the unmodified ur_rtde library and that socket, judged by the twin's physics judge."""

from __future__ import annotations

import socket

import numpy as np
import pytest

from tests.twin.conftest import TwinProcess
from tests.twin.robotiq_cpp_replica import AT_DEST, STOPPED_INNER_OBJECT, RobotiqReplica

pytestmark = [pytest.mark.sim, pytest.mark.real_client]
rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")

HOME = [0.0, -1.9, 1.9, -1.57, -1.57, 0.0]


def test_the_cpp_clients_sequence_activates_moves_and_reads(twin: TwinProcess) -> None:
    gripper = RobotiqReplica(twin.host)
    try:
        gripper.activate()  # reset, ACT 1, 1 s, poll until STA 3, dump the variables
        assert gripper.is_active()
        assert gripper.move(255, 255, 50) == AT_DEST  # closes on nothing: at the requested (closed) position
        assert gripper.get_var("POS") == 230  # the real 2F-85's closed count
        assert gripper.move(0, 255, 50) == AT_DEST
        assert gripper.get_vars(["POS", "PRE", "OBJ", "FLT", "STA"]) == [3, 0, AT_DEST, 0, 3]
        assert gripper.move(128, 255, 50) == AT_DEST
        width = float(twin.control("status")["gripper_opening_m"])  # type: ignore[arg-type]
        assert width == pytest.approx(0.085 * (230 - 128) / 227, abs=0.001)
        assert gripper.move(0, 255, 50) == AT_DEST
    finally:
        gripper.close()


def test_bad_requests_are_answered_and_refused_in_one_sentence(twin: TwinProcess) -> None:
    with socket.create_connection((twin.host, 63352), timeout=2) as raw:
        for request in (b"GET XYZ\n", b"SET POS 300\n", b"HELLO\n"):
            raw.sendall(request)
            assert raw.recv(1024) == b"?"
        raw.sendall(b"SET SPE 100\n")
        assert raw.recv(1024) == b"ack"  # still served
    log = twin.log()
    assert "GET of unknown variable 'XYZ'" in log and "SET POS '300': a value is a whole number 0..255" in log
    with socket.create_connection((twin.host, 63352), timeout=2) as raw:
        raw.sendall(b"G" * 300)  # no line end, beyond a line's bound: refused and closed
        assert raw.recv(1024) == b""
    assert "300 bytes without a line end on the gripper socket" in twin.log()


@pytest.mark.slow
def test_a_pick_through_ur_rtde_and_the_gripper_socket_is_judged_a_success(twin: TwinProcess) -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    # where the twin (seed 0) put the red box: the same world, built here, read through the oracle (a test may)
    T_box = GroundTruthOracle(World.from_file("scenes/tabletop.yaml", 0)).T_world_object("red_box")
    x, y = -T_box[0, 3], -T_box[1, 3]  # UR's base frame is base_link turned by pi about z
    yaw = float(np.arctan2(T_box[1, 0], T_box[0, 0])) + np.pi
    turn = (yaw + np.pi / 2 + np.pi / 4) % (np.pi / 2) - np.pi / 4  # close across a face, least wrist turn

    def down(z: float) -> list[float]:
        R = np.array([[np.cos(turn), -np.sin(turn), 0], [np.sin(turn), np.cos(turn), 0], [0, 0, 1]]) @ np.diag(
            [1.0, -1.0, -1.0])
        angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
        axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
        if np.linalg.norm(axis) < 1e-9:  # a half turn: the axis from the diagonal
            axis = np.sqrt(np.clip((np.diag(R) + 1) / 2, 0, None)) * [1, np.sign(R[0, 1]) or 1, np.sign(R[0, 2]) or 1]
        return [x, y, z, *(axis / np.linalg.norm(axis) * angle)]

    c = rtde_control.RTDEControlInterface(twin.host)
    r = rtde_receive.RTDEReceiveInterface(twin.host)
    gripper = RobotiqReplica(twin.host)
    try:
        gripper.activate()
        assert gripper.move(0, 255, 24) == AT_DEST  # FOR 24: 40 N, the scene's grip force
        assert c.moveJ(HOME, 1.5, 3.0)
        assert c.moveJ(c.getInverseKinematics(down(0.15)), 1.5, 3.0)
        assert c.moveL(down(0.03), 0.5, 2.0)  # finger tips 1 cm above the table
        assert gripper.move(255, 255, 24) == STOPPED_INNER_OBJECT  # stopped on the box
        assert c.moveL(down(0.20), 0.5, 2.0)
        verdict = twin.control('judge {"kind": "pick", "color": "red", "height_m": 0.15}')
        assert verdict["success"], verdict
        assert verdict["object"] == "red_box" and verdict["in_gripper"]
        assert c.moveL(down(0.035), 0.5, 2.0)  # put it back for the tests after this one
        assert gripper.move(0, 255, 24) == AT_DEST
        assert c.moveL(down(0.15), 0.5, 2.0)
        assert c.moveJ(HOME, 1.5, 3.0)
    finally:
        gripper.close()
        c.stopScript()
        c.disconnect()
        r.disconnect()
