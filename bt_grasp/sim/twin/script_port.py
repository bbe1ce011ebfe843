"""Port 30003: where a client sends a URScript program (ur_rtde's ``ScriptClient``).

A program is ``def name():`` up to the first line that is exactly ``end``; a line sent outside a ``def`` is a
one-line program. Each complete program goes to :func:`bt_grasp.sim.twin.control_script.recognise`: ur_rtde
1.6.5's control script starts the twin's program (replacing a running one, as a controller does); anything else is
refused with one logged sentence. A program larger than :data:`MAX_PROGRAM_BYTES` is refused and the connection
closed. Nothing is sent back (a controller streams its 1108-byte state packages on this port; ur_rtde never
reads them, and the twin does not send them).
"""

from __future__ import annotations

import logging
import time

from bt_grasp.sim.twin.control_script import recognise
from bt_grasp.sim.twin.controller import Controller
from bt_grasp.sim.twin.netio import Link, Refused, Session

log = logging.getLogger(__name__)

MAX_PROGRAM_BYTES = 256 * 1024


class ScriptSession(Session):
    def __init__(self, link: Link, controller: Controller) -> None:
        super().__init__(link)
        self.controller = controller
        self._buffer = bytearray()
        self._partial_since: float | None = None

    def partial_since(self) -> float | None:
        return self._partial_since

    def on_bytes(self, data: bytes) -> None:
        self._buffer += data
        while True:
            program = self._take_program()
            if program is None:
                break
            self._run(program)
        if len(self._buffer) > MAX_PROGRAM_BYTES:
            raise Refused(f"a program of more than {MAX_PROGRAM_BYTES} bytes on the script port")
        self._partial_since = (self._partial_since or time.monotonic()) if self._buffer.strip() else None
        if not self._buffer.strip():
            self._buffer.clear()

    def _take_program(self) -> bytes | None:
        text = self._buffer
        start = len(text) - len(text.lstrip())
        if start == len(text):
            return None
        if not text[start:].startswith(b"def "):
            end = text.find(b"\n", start)
            if end < 0:
                return None
            program = bytes(text[start:end + 1])
            del text[:end + 1]
            return program
        pos = start
        while (end := text.find(b"\n", pos)) >= 0:
            if text[pos:end].rstrip(b"\r") == b"end":
                program = bytes(text[start:end + 1])
                del text[:end + 1]
                return program
            pos = end + 1
        return None

    def _run(self, program: bytes) -> None:
        text = program.decode("utf-8", "replace")
        found = recognise(text)
        if isinstance(found, str):
            log.warning("script from %s refused: %s", self.link.peer, found)
            return
        refusal = self.controller.load_program(found)
        if refusal is not None:
            log.warning("script from %s refused: %s", self.link.peer, refusal)
