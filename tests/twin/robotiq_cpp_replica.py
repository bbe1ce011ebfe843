"""The Robotiq URCap socket as ur_rtde's C++ ``robotiq_gripper.cpp`` (1.6.5) speaks it, replicated request for
request (the Python wheel has no Robotiq client): ``GET VAR\\n`` read once and split on a space, ``SET ...\\n``
compared with ``"ack"`` whole, ``activate()``'s reset/ACT/1 s wait/poll sequence, ``move()``'s one SET of POS,
SPE, FOR, GTO then polling PRE and OBJ, ``getVars`` as several GET lines in one write and one read. The only
addition is a socket timeout (the C++ client blocks forever on a silent gripper)."""

from __future__ import annotations

import socket
import time

ACTIVE = 3
MOVING, STOPPED_OUTER_OBJECT, STOPPED_INNER_OBJECT, AT_DEST = 0, 1, 2, 3


class RobotiqReplica:
    def __init__(self, host: str, port: int = 63352, timeout_s: float = 2.0) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout_s)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def close(self) -> None:
        self.sock.close()

    def _receive(self) -> str:  # RobotiqGripper::receive: one read_some of up to 1024 bytes
        return self.sock.recv(1024).decode()

    def get_var(self, var: str) -> int:
        self.sock.sendall(f"GET {var}\n".encode())
        rx = self._receive()
        if not rx:
            raise ConnectionError("Empty response")
        data = rx.split(" ")
        if data[0] != var:
            raise ValueError(f"Unexpected response: data {data[0]} does not match {var}")
        if data[1][0] == "?":
            raise ValueError("Reading gripper values not possible in current device state.")
        return int(data[1])

    def get_vars(self, names: list[str]) -> list[int]:
        self.sock.sendall("".join(f"GET {n}\n" for n in names).encode())
        return [int(line.split(" ")[1]) for line in self._receive().split("\n") if line]

    def set_vars(self, pairs: list[tuple[str, int]]) -> bool:
        self.sock.sendall(("SET" + "".join(f" {k} {v}" for k, v in pairs) + "\n").encode())
        return self._receive() == "ack"

    def is_active(self) -> bool:
        return self.get_var("STA") == ACTIVE

    def reset(self) -> None:
        self.set_vars([("ACT", 0)])
        self.set_vars([("ATR", 0)])
        while self.get_var("ACT") != 0 or self.get_var("STA") != 0:
            self.set_vars([("ACT", 0)])
            self.set_vars([("ATR", 0)])
            time.sleep(0.01)
        time.sleep(0.5)

    def activate(self) -> None:
        if not self.is_active():
            self.reset()
            while self.get_var("ACT") != 0 or self.get_var("STA") != 0:
                time.sleep(0.01)
            self.set_vars([("ACT", 1)])
            time.sleep(1.0)
            while self.get_var("ACT") != 1 or self.get_var("STA") != ACTIVE:
                time.sleep(0.01)
        for var in ("ACT", "GTO", "FOR", "SPE", "POS", "STA", "PRE", "OBJ", "FLT"):  # dumpVars
            self.get_var(var)

    def move(self, position: int, speed: int, force: int, wait: bool = True) -> int:
        if not self.set_vars([("POS", position), ("SPE", speed), ("FOR", force), ("GTO", 1)]):
            raise RuntimeError("Failed to set variables for gripper move")
        while self.get_var("PRE") != position:
            time.sleep(0.001)
        if not wait:
            return self.get_var("OBJ")
        status = self.get_var("OBJ")
        while status == MOVING:
            time.sleep(0.01)
            status = self.get_var("OBJ")
        return status
