"""The Robotiq client's reads are bounded: a gripper that answers nothing is GRIPPER_NOT_ANSWERING within its
timeout, one that answers outside the protocol is one sentence, one that reports a fault is GRIPPER_FAULT. The
server here is a few lines of socket code speaking the URCap's protocol (the client is also driven against the
twin's gripper port by tests/realcell/test_cell_on_twin.py)."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, Iterator

import pytest

from bt_grasp.hardware.cell_faults import CellFault, CellFaultKind, CellUnavailable
from bt_grasp.hardware.robotiq_client import Robotiq2F85Client

Answer = Callable[[bytes], bytes | None]


@pytest.fixture
def gripper() -> Iterator[Callable[[Answer], tuple[str, int]]]:
    servers: list[socket.socket] = []

    def serve(answer: Answer) -> tuple[str, int]:
        server = socket.socket()
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        servers.append(server)

        def loop() -> None:
            try:
                conn, _ = server.accept()
                with conn:
                    buffer = b""
                    while chunk := conn.recv(256):
                        buffer += chunk
                        while b"\n" in buffer:
                            line, buffer = buffer.split(b"\n", 1)
                            reply = answer(line)
                            if reply is not None:
                                conn.sendall(reply)
            except OSError:  # the client closed its end
                return

        threading.Thread(target=loop, daemon=True).start()
        host, port = server.getsockname()
        return str(host), int(port)

    yield serve
    for server in servers:
        server.close()


def _healthy(fault: int = 0, pos: int = 3) -> Answer:
    def answer(line: bytes) -> bytes:
        words = line.decode().split()
        if words[0] == "SET":
            return b"ack"
        value = {"STA": 3, "POS": pos, "OBJ": 3, "FLT": fault}.get(words[1], 0)
        return f"{words[1]} {value}\n".encode()

    return answer


def test_a_healthy_gripper_opens_closes_and_reports_its_width(gripper) -> None:  # type: ignore[no-untyped-def]
    host, port = gripper(_healthy(pos=230))
    client = Robotiq2F85Client(host, port, 0.085)
    client.connect()
    assert client.status.width_m == 0.0  # 230 counts: the pads together
    client.close_on(40.0)
    assert client.target_width_m == 0.0 and client.force_counts(40.0) == round(20 / 215 * 255)
    client.close()


def test_a_silent_gripper_is_not_answering_within_its_timeout(gripper) -> None:  # type: ignore[no-untyped-def]
    silent = [False]
    healthy = _healthy()
    host, port = gripper(lambda line: None if silent[0] else healthy(line))
    client = Robotiq2F85Client(host, port, 0.085, answer_timeout_s=0.1)
    client.connect()
    silent[0] = True
    start = time.monotonic()
    with pytest.raises(CellFault) as caught:
        client.poll()
    assert caught.value.kind is CellFaultKind.GRIPPER_NOT_ANSWERING
    assert time.monotonic() - start < 0.5
    client.close()


@pytest.mark.parametrize(("answer", "kind", "says"), [
    (lambda line: b"POS banana\n", CellFaultKind.GRIPPER_FAULT, "expected 'POS n'"),
    (lambda line: b"x" * 300, CellFaultKind.GRIPPER_FAULT, "unasked for"),
])
def test_answers_outside_the_protocol_are_one_sentence(gripper, answer: Answer, kind: CellFaultKind,  # type: ignore[no-untyped-def]
                                                       says: str) -> None:
    healthy = _healthy()
    host, port = gripper(lambda line: healthy(line) if line.startswith((b"SET", b"GET STA")) else answer(line))
    client = Robotiq2F85Client(host, port, 0.085)
    with pytest.raises(CellUnavailable, match=says):
        client.connect()  # activation reads STA, then the first poll meets the bad answer


def test_a_gripper_fault_ends_the_run(gripper) -> None:  # type: ignore[no-untyped-def]
    host, port = gripper(_healthy(fault=0x0E))  # overcurrent
    client = Robotiq2F85Client(host, port, 0.085)
    with pytest.raises(CellUnavailable, match="fault 0x0e"):
        client.connect()


def test_nothing_listening_is_one_sentence() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(CellUnavailable, match=r"cannot be reached .* URCap"):
        Robotiq2F85Client("127.0.0.1", port, 0.085).connect(connect_timeout_s=0.5)
