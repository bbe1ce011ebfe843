"""The twin's own control port (not a UR port): faults, the judge, the camera, the twin's status.

One request per line, one JSON object per line back: ``{"ok": true, ...}`` or ``{"ok": false, "error": "..."}``.

    status                            the controller's modes, the measured period, the camera's frames
    fault protective-stop             (and pendant-stop, drop-connections [SECONDS], gripper-silent,
                                      gripper-answers: bt_grasp.sim.twin.faults)
    goal                              the goal the judge checks unless a run names one (the scene's, or a pick)
    judge                             the verdict on the scene's goal, or a pick of the default colour
    judge {"kind": "pick", ...}       the verdict on that goal (a scene file's goal, as JSON)
    camera capture                    render one frame now
    camera on [HZ] | camera off       render continuously (default 15 Hz) or stop
    truth camera                      the true camera pose (ground truth: for tests and benchmarks only)
"""

from __future__ import annotations

import json
import logging
import time
from typing import Any, Protocol

from bt_grasp.sim.twin.faults import TwinFault
from bt_grasp.sim.twin.netio import Link, Refused, Session

log = logging.getLogger(__name__)

MAX_LINE_BYTES = 4096


class RequestError(Exception):
    """A control request the twin cannot carry out: the text is the reply's one sentence."""


class TwinControl(Protocol):
    def status(self) -> dict[str, Any]: ...

    def inject(self, fault: TwinFault, seconds: float | None) -> str: ...

    def judge(self, goal_json: str | None) -> dict[str, Any]: ...

    def goal(self) -> dict[str, Any]: ...

    def camera(self, action: str, rate_hz: float | None) -> dict[str, Any]: ...

    def truth(self, what: str) -> dict[str, Any]: ...


class ControlSession(Session):
    def __init__(self, link: Link, twin: TwinControl) -> None:
        super().__init__(link)
        self.twin = twin
        self._buffer = bytearray()
        self._partial_since: float | None = None

    def partial_since(self) -> float | None:
        return self._partial_since

    def on_bytes(self, data: bytes) -> None:
        self._buffer += data
        while (end := self._buffer.find(b"\n")) >= 0:
            raw = bytes(self._buffer[:end]).strip()
            del self._buffer[:end + 1]
            if len(raw) > MAX_LINE_BYTES:
                raise Refused(f"a control request of {len(raw)} bytes; the twin takes at most {MAX_LINE_BYTES}")
            try:
                reply = {"ok": True, **self._handle(raw.decode("utf-8"))}
            except (RequestError, UnicodeDecodeError) as exc:
                log.warning("control client %s: %s", self.link.peer, exc)
                reply = {"ok": False, "error": str(exc)}
            self.link.send((json.dumps(reply) + "\n").encode())
        if len(self._buffer) > MAX_LINE_BYTES:
            raise Refused(f"{len(self._buffer)} bytes without a line end on the control port")
        self._partial_since = (self._partial_since or time.monotonic()) if self._buffer else None

    def _handle(self, line: str) -> dict[str, Any]:
        words = line.split(maxsplit=1)
        if not words:
            raise RequestError("an empty request; expected status, fault, goal, judge, camera or truth")
        verb, rest = words[0], (words[1] if len(words) > 1 else "")
        if verb == "status" and not rest:
            return self.twin.status()
        if verb == "fault":
            parts = rest.split()
            try:
                fault = TwinFault(parts[0]) if parts else None
            except ValueError:
                fault = None
            if fault is None:
                raise RequestError(f"unknown fault {rest!r}; expected one of {', '.join(f.value for f in TwinFault)}")
            seconds = None
            if len(parts) == 2 and fault == TwinFault.DROP_CONNECTIONS:
                try:
                    seconds = float(parts[1])
                except ValueError:
                    seconds = -1.0
                if not 0.0 <= seconds <= 600.0:
                    raise RequestError(f"drop-connections takes 0 to 600 seconds, got {parts[1]!r}")
            elif len(parts) > 1:
                raise RequestError(f"fault {fault.value} takes no argument")
            return {"fault": fault.value, "done": self.twin.inject(fault, seconds)}
        if verb == "judge":
            return self.twin.judge(rest or None)
        if verb == "camera":
            parts = rest.split()
            if parts[:1] == ["on"] and len(parts) <= 2:
                try:
                    rate = float(parts[1]) if len(parts) == 2 else None
                except ValueError:
                    rate = -1.0
                if rate is not None and not 0.1 <= rate <= 60.0:
                    raise RequestError(f"camera on takes a rate of 0.1 to 60 Hz, got {parts[1]!r}")
                return self.twin.camera("on", rate)
            if parts in (["off"], ["capture"]):
                return self.twin.camera(parts[0], None)
            raise RequestError(f"camera takes on [HZ], off or capture, got {rest!r}")
        if verb == "goal" and not rest:
            return self.twin.goal()
        if verb == "truth":
            return self.twin.truth(rest)
        raise RequestError(f"unknown request {verb!r}; expected status, fault, goal, judge, camera or truth")
