"""Port 63352: the Robotiq URCap's ASCII socket, as ur_rtde's ``robotiq_gripper.cpp`` speaks to it.

``GET VAR\\n`` is answered ``VAR n\\n``; ``SET VAR n [VAR n ...]\\n`` is answered ``ack`` (no line end: the C++
client compares the whole read with ``"ack"``). Several requests in one read are answered in one write, in
order (``getVars`` sends its ``GET`` lines together and reads once). A value outside 0..255, an unknown variable
or a line that is neither request is refused with one logged sentence and answered ``?``; the connection stays
open. More than :data:`MAX_LINE_BYTES` without a line end closes it.

The "gripper stops answering" fault leaves the connection open and answers nothing.
"""

from __future__ import annotations

import logging
import threading
import time

from bt_grasp.sim.twin.netio import Link, Refused, Session
from bt_grasp.sim.twin.robotiq import READABLE, WRITABLE, Robotiq2F85

log = logging.getLogger(__name__)

MAX_LINE_BYTES = 256


class GripperSilence:
    """The "gripper stops answering" fault's switch, shared by every gripper connection."""

    def __init__(self) -> None:
        self._on = threading.Event()

    @property
    def on(self) -> bool:
        return self._on.is_set()

    def set(self, on: bool) -> None:
        if on:
            self._on.set()
        else:
            self._on.clear()


class GripperSession(Session):
    def __init__(self, link: Link, device: Robotiq2F85, silence: GripperSilence) -> None:
        super().__init__(link)
        self.device = device
        self.silence = silence
        self._buffer = bytearray()
        self._partial_since: float | None = None

    def partial_since(self) -> float | None:
        return self._partial_since

    def on_bytes(self, data: bytes) -> None:
        self._buffer += data
        replies: list[bytes] = []
        while (end := self._buffer.find(b"\n")) >= 0:
            line = bytes(self._buffer[:end]).rstrip(b"\r")
            del self._buffer[:end + 1]
            if len(line) > MAX_LINE_BYTES:
                raise Refused(f"a gripper request of {len(line)} bytes; the twin takes lines of at most "
                              f"{MAX_LINE_BYTES}")
            replies.append(self._answer(line))
        if len(self._buffer) > MAX_LINE_BYTES:
            raise Refused(f"{len(self._buffer)} bytes without a line end on the gripper socket")
        self._partial_since = (self._partial_since or time.monotonic()) if self._buffer else None
        if replies and not self.silence.on:
            self.link.send(b"".join(replies))

    def _refuse(self, sentence: str) -> bytes:
        log.warning("gripper client %s: %s", self.link.peer, sentence)
        return b"?"

    def _answer(self, line: bytes) -> bytes:
        try:
            words = line.decode("ascii").split()
        except UnicodeDecodeError:
            return self._refuse("a request that is not ASCII was refused")
        if len(words) == 2 and words[0] == "GET":
            name = words[1]
            if name not in READABLE:
                return self._refuse(f"GET of unknown variable {name!r}; readable: {', '.join(READABLE)}")
            return f"{name} {self.device.get(name)}\n".encode()
        if len(words) >= 3 and words[0] == "SET" and len(words) % 2 == 1:
            assignments: list[tuple[str, int]] = []
            for name, text in zip(words[1::2], words[2::2], strict=True):
                if name not in WRITABLE:
                    return self._refuse(f"SET of unknown variable {name!r}; writable: {', '.join(WRITABLE)}")
                if not text.isdigit() or not 0 <= int(text) <= 255:
                    return self._refuse(f"SET {name} {text!r}: a value is a whole number 0..255")
                assignments.append((name, int(text)))
            self.device.set(assignments)
            return b"ack"
        return self._refuse(f"a request that is neither 'GET VAR' nor 'SET VAR n ...': {line[:40]!r}")
