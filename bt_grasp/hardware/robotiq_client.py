"""A Robotiq 2F-85 through its URCap's socket (port 63352 on the robot): activate, position, speed, force, object
detection, faults.

The URCap speaks one ASCII request a line: ``GET VAR`` answered ``VAR n``, ``SET VAR n [VAR n ...]`` answered
``ack`` (no line end). ``ACT`` activates, ``GTO`` goes, ``POS`` 0..255 (open .. closed), ``SPE`` and ``FOR`` 0..255
span the gripper's speed and force ranges; ``STA`` (3 active), ``OBJ`` (0 moving, 1/2 stopped on an object while
opening/closing, 3 at the request), ``FLT`` (0 no fault) and ``POS`` read back. ur_rtde's Python wheel has no client
(its ``robotiq_gripper.cpp`` is C++ only, and waits forever on a silent gripper); this one bounds every read: a
reply that does not come within ``answer_timeout_s`` is :data:`~bt_grasp.hardware.cell_faults.CellFaultKind`
``GRIPPER_NOT_ANSWERING``, a reply that is not the protocol's is one sentence, and a fault the gripper reports is
``GRIPPER_FAULT``.

Width and counts: the fingers' travel is ``open_counts`` (fully open, the stroke apart) to ``closed_counts`` (the
pads together), linear between (the 2F-85's 3 .. 230; a request of 255 closes until the pads meet something).
"""

from __future__ import annotations

import logging
import socket
import time
from dataclasses import dataclass

from bt_grasp.hardware.cell_faults import CellFault, CellFaultKind, CellUnavailable

log = logging.getLogger(__name__)

#: a reply line is at most this long (``VAR 255``: 7 bytes); more without a line end is not the protocol
MAX_REPLY_BYTES = 256
#: activation (the gripper opens and closes once to find its stroke) takes at most this long
ACTIVATION_TIMEOUT_S = 10.0
#: Robotiq's fault codes that stop the gripper (``FLT`` 0x08 and above: temperature, communication, voltage, release,
#: internal, activation, overcurrent); 0x05 and 0x07 are requests made too early, logged only
MAJOR_FAULT = 0x08


class GripperSocketClosed(CellFault):
    """The gripper's socket was closed or reset (not merely silent): the controller itself may be gone."""

    def __init__(self, detail: str) -> None:
        super().__init__(CellFaultKind.GRIPPER_NOT_ANSWERING, detail)


@dataclass(frozen=True)
class GripperStatus:
    """One poll: the finger opening (m), the object detection (``OBJ``) and the fault code (``FLT``)."""

    width_m: float
    obj: int
    fault: int


class Robotiq2F85Client:
    """The gripper's socket client; :meth:`connect` opens and activates, :meth:`poll` once a control period."""

    def __init__(self, host: str, port: int, stroke_m: float, force_range_n: tuple[float, float] = (20.0, 235.0),
                 answer_timeout_s: float = 0.1, open_counts: int = 3, closed_counts: int = 230) -> None:
        self.host, self.port = host, port
        self.stroke_m = stroke_m
        self.force_range_n = force_range_n
        self.answer_timeout_s = answer_timeout_s
        self.open_counts, self.closed_counts = open_counts, closed_counts
        self._sock: socket.socket | None = None
        self._buffer = b""
        self.status = GripperStatus(stroke_m, 3, 0)
        self.target_width_m = stroke_m

    # -- life -------------------------------------------------------------------------------------------------
    def connect(self, connect_timeout_s: float = 3.0) -> None:
        """Open the socket and activate the gripper (if it is not active); CellUnavailable when it cannot be."""
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=connect_timeout_s)
        except OSError as exc:
            raise CellUnavailable(f"the gripper at {self.host}:{self.port} cannot be reached ({exc.strerror or exc}): "
                                  "is the Robotiq URCap installed and the robot on?") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            if self.get("STA") != 3:
                self.set(("ACT", 1))
                deadline = time.monotonic() + ACTIVATION_TIMEOUT_S
                while self.get("STA") != 3:
                    if time.monotonic() > deadline:
                        raise CellUnavailable(f"the gripper at {self.host}:{self.port} did not activate within "
                                              f"{ACTIVATION_TIMEOUT_S:g} s")
                    time.sleep(0.02)
            self.set(("GTO", 1))
            self.poll()
        except CellFault as fault:
            self.close()
            raise CellUnavailable(f"the gripper at {self.host}:{self.port}: {fault.detail}") from None

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    # -- commands -----------------------------------------------------------------------------------------------
    def width_to_counts(self, width_m: float) -> int:
        span = self.closed_counts - self.open_counts
        counts = self.closed_counts - width_m / self.stroke_m * span
        return round(min(max(counts, self.open_counts), self.closed_counts))

    def counts_to_width(self, counts: int) -> float:
        c = min(max(counts, self.open_counts), self.closed_counts)
        return self.stroke_m * (self.closed_counts - c) / (self.closed_counts - self.open_counts)

    def force_counts(self, force_n: float) -> int:
        lo, hi = self.force_range_n
        return round(min(max((force_n - lo) / (hi - lo), 0.0), 1.0) * 255)

    def open(self) -> None:
        self.target_width_m = self.stroke_m
        self.set(("POS", self.open_counts), ("SPE", 255), ("FOR", 100), ("GTO", 1))

    def close_on(self, force_n: float) -> None:
        """Close until the pads meet something, pressing with ``force_n`` (clipped to the gripper's range)."""
        self.target_width_m = 0.0
        self.set(("POS", 255), ("SPE", 255), ("FOR", self.force_counts(force_n)), ("GTO", 1))

    def poll(self) -> GripperStatus:
        """Read the opening, object detection and fault (one request of three ``GET`` lines)."""
        values = self.get_many("POS", "OBJ", "FLT")
        status = GripperStatus(self.counts_to_width(values["POS"]), values["OBJ"], values["FLT"])
        if status.fault >= MAJOR_FAULT:
            raise CellFault(CellFaultKind.GRIPPER_FAULT, f"the gripper reports fault {status.fault:#04x} (FLT)")
        if status.fault and status.fault != self.status.fault:
            log.warning("the gripper reports %#04x (a request before activation finished)", status.fault)
        self.status = status
        return status

    # -- the protocol -------------------------------------------------------------------------------------------
    def get(self, name: str) -> int:
        return self.get_many(name)[name]

    def get_many(self, *names: str) -> dict[str, int]:
        self._send("".join(f"GET {n}\n" for n in names))
        out: dict[str, int] = {}
        for name in names:
            line = self._read_line()
            parts = line.split(" ")
            if len(parts) != 2 or parts[0] != name or not parts[1].isdigit() or int(parts[1]) > 255:
                raise CellFault(CellFaultKind.GRIPPER_FAULT, f"the gripper answered {line[:40]!r} to GET {name} "
                                                             f"(expected '{name} n')")
            out[name] = int(parts[1])
        return out

    def set(self, *assignments: tuple[str, int]) -> None:
        self._send("SET" + "".join(f" {k} {int(v)}" for k, v in assignments) + "\n")
        reply = self._read_exact(3)
        if reply != b"ack":
            raise CellFault(CellFaultKind.GRIPPER_FAULT, f"the gripper answered {reply[:40]!r} to SET (expected ack)")

    def _send(self, text: str) -> None:
        if self._sock is None:
            raise CellFault(CellFaultKind.GRIPPER_NOT_ANSWERING, "the gripper's socket is not open")
        try:
            self._sock.settimeout(self.answer_timeout_s)
            self._sock.sendall(text.encode("ascii"))
        except OSError as exc:
            raise GripperSocketClosed(f"the gripper's socket failed ({exc.strerror or exc})") from None

    def _fill(self, deadline: float) -> None:
        assert self._sock is not None
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError
        self._sock.settimeout(left)
        chunk = self._sock.recv(MAX_REPLY_BYTES)
        if not chunk:
            raise ConnectionError("the gripper closed its socket")
        self._buffer += chunk
        if len(self._buffer) > MAX_REPLY_BYTES:
            raise CellFault(CellFaultKind.GRIPPER_FAULT, f"the gripper sent {len(self._buffer)} bytes unasked for")

    def _read(self, ready: int | None) -> bytes:
        """``ready``: bytes wanted (None: a line)."""
        deadline = time.monotonic() + self.answer_timeout_s
        try:
            while True:
                if ready is None and (end := self._buffer.find(b"\n")) >= 0:
                    out, self._buffer = self._buffer[:end], self._buffer[end + 1:]
                    return out
                if ready is not None and len(self._buffer) >= ready:
                    out, self._buffer = self._buffer[:ready], self._buffer[ready:]
                    return out
                self._fill(deadline)
        except TimeoutError:
            self._buffer = b""
            raise CellFault(CellFaultKind.GRIPPER_NOT_ANSWERING,
                            f"no answer within {self.answer_timeout_s * 1000:.0f} ms") from None
        except (ConnectionError, OSError) as exc:
            raise GripperSocketClosed(f"the gripper's socket failed ({exc})") from None

    def _read_line(self) -> str:
        return self._read(None).decode("ascii", "replace").strip()

    def _read_exact(self, count: int) -> bytes:
        return self._read(count)
