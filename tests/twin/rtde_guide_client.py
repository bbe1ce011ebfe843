"""An RTDE client written from Universal Robots' RTDE guide (protocol version 2), for checking the twin's layouts.

Deliberately independent of ``bt_grasp.sim.twin``: its own type sizes, its own package framing, its own parsing,
all from the guide's text ("Header: uint16 package size, uint8 package type"; "RTDE_CONTROL_PACKAGE_SETUP_OUTPUTS:
double output frequency, string variable names; returns uint8 output recipe id, string variable types"; ...).
"""

from __future__ import annotations

import socket
import struct
import time
from dataclasses import dataclass, field

# the guide's package types (ASCII)
V, v, M, U, O, I, S, P = (ord(c) for c in "VvMUOISP")  # noqa: E741
# the guide's data types and their serialisation (big-endian)
GUIDE_TYPES = {
    "BOOL": "?", "UINT8": "B", "UINT32": "I", "UINT64": "Q", "INT32": "i", "DOUBLE": "d",
    "VECTOR3D": "ddd", "VECTOR6D": "dddddd", "VECTOR6INT32": "iiiiii", "VECTOR6UINT32": "IIIIII",
}


class GuideError(Exception):
    pass


@dataclass
class GuideClient:
    host: str
    port: int = 30004
    timeout_s: float = 5.0
    sock: socket.socket = field(init=False)
    _pending: bytes = b""

    def __post_init__(self) -> None:
        self.sock = socket.create_connection((self.host, self.port), timeout=self.timeout_s)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def close(self) -> None:
        self.sock.close()

    # --- framing -----------------------------------------------------------------------------------------
    def send(self, kind: int, payload: bytes = b"") -> None:
        self.sock.sendall(struct.pack(">HB", 3 + len(payload), kind) + payload)

    def _read(self, n: int) -> bytes:
        while len(self._pending) < n:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise GuideError("the controller closed the connection")
            self._pending += chunk
        out, self._pending = self._pending[:n], self._pending[n:]
        return out

    def receive(self) -> tuple[int, bytes, float]:
        """(package type, payload, arrival time (perf_counter) of the package's header)."""
        header = self._read(3)
        arrived = time.perf_counter()
        size, kind = struct.unpack(">HB", header)
        if size < 3:
            raise GuideError(f"a package declares {size} bytes, less than its header")
        return kind, self._read(size - 3), arrived

    def expect(self, kind: int) -> bytes:
        got, payload, _ = self.receive()
        if got != kind:
            raise GuideError(f"expected package {chr(kind)!r}, got {chr(got)!r} ({payload[:60]!r})")
        return payload

    # --- the guide's requests ----------------------------------------------------------------------------
    def request_protocol_version(self, version: int = 2) -> bool:
        self.send(V, struct.pack(">H", version))
        payload = self.expect(V)
        if len(payload) != 1:
            raise GuideError(f"RTDE_REQUEST_PROTOCOL_VERSION returns one uint8, got {len(payload)} bytes")
        return payload[0] == 1

    def urcontrol_version(self) -> tuple[int, int, int, int]:
        self.send(v)
        payload = self.expect(v)
        if len(payload) != 16:
            raise GuideError(f"RTDE_GET_URCONTROL_VERSION returns four uint32, got {len(payload)} bytes")
        major, minor, bugfix, build = struct.unpack(">IIII", payload)
        return major, minor, bugfix, build

    def setup_outputs(self, names: list[str], frequency_hz: float) -> tuple[int, list[str]]:
        self.send(O, struct.pack(">d", frequency_hz) + ",".join(names).encode("ascii"))
        payload = self.expect(O)
        return payload[0], payload[1:].decode("ascii").split(",")

    def setup_inputs(self, names: list[str]) -> tuple[int, list[str]]:
        self.send(I, ",".join(names).encode("ascii"))
        payload = self.expect(I)
        return payload[0], payload[1:].decode("ascii").split(",")

    def start(self) -> bool:
        self.send(S)
        payload = self.expect(S)
        return len(payload) == 1 and payload[0] == 1

    def pause(self) -> bool:
        self.send(P)
        while True:  # data packages may still be in flight before the pause's answer
            kind, payload, _ = self.receive()
            if kind == P:
                return len(payload) == 1 and payload[0] == 1
            if kind != U:
                raise GuideError(f"expected the pause's answer, got package {chr(kind)!r}")

    def send_inputs(self, recipe_id: int, types: list[str], values: list[object]) -> None:
        fmt = ">B" + "".join(GUIDE_TYPES[t] for t in types)
        flat: list[object] = [recipe_id]
        for t, value in zip(types, values, strict=True):
            flat.extend(value if len(GUIDE_TYPES[t]) > 1 else [value])  # type: ignore[call-overload]
        self.send(U, struct.pack(fmt, *flat))

    def text_message(self, message: str, source: str = "guide", level: int = 3) -> None:
        m, s = message.encode(), source.encode()
        self.send(M, bytes([len(m)]) + m + bytes([len(s)]) + s + bytes([level]))

    @staticmethod
    def parse_data(payload: bytes, types: list[str]) -> tuple[int, list[object]]:
        """(recipe id, one value per field: a tuple for vectors)."""
        fmt = ">B" + "".join(GUIDE_TYPES[t] for t in types)
        if struct.calcsize(fmt) != len(payload):
            raise GuideError(f"a data package of {len(payload)} bytes; the recipe's types make {struct.calcsize(fmt)}")
        flat = struct.unpack(fmt, payload)
        values: list[object] = []
        i = 1
        for t in types:
            n = len(GUIDE_TYPES[t])
            values.append(flat[i] if n == 1 else tuple(flat[i:i + n]))
            i += n
        return flat[0], values
