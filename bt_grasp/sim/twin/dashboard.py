"""Port 29999: the dashboard server, one command per line, one line back (PolyScope 3.x wording).

The replies are the ones ur_rtde's ``DashboardClient`` checks (``Stopped``, ``Starting program``, ``Protective
stop releasing``, ``Loading program: ...``) and the state queries it parses. The twin has no program files:
``load`` answers ``File not found`` and ``play`` only resumes a paused control script. Commands of PolyScope 5.6+
(``get serial number``, ``is in remote control``, ``get robot model``) are answered too, though ur_rtde asks them
only of a 5.x controller. An unknown command is answered ``could not understand: '<line>'``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from bt_grasp.sim.twin.config import ControllerModel
from bt_grasp.sim.twin.controller import Controller
from bt_grasp.sim.twin.netio import Link, Refused, Session
from bt_grasp.sim.twin.state import RuntimeState, SafetyMode

log = logging.getLogger(__name__)

MAX_LINE_BYTES = 1024
WELCOME = "Connected: Universal Robots Dashboard Server"


class DashboardSession(Session):
    def __init__(self, link: Link, controller: Controller, model: ControllerModel) -> None:
        super().__init__(link)
        self.controller = controller
        self.model = model
        self._buffer = bytearray()
        self._partial_since: float | None = None
        self._commands: dict[str, Callable[[str], str]] = {
            "PolyscopeVersion": lambda _: self.model.software,
            "get serial number": lambda _: self.model.serial_number,
            "get robot model": lambda _: self.model.robot_model,
            "is in remote control": lambda _: "true",
            "robotmode": lambda _: f"Robotmode: {self.controller.robot_mode.name}",
            "safetymode": lambda _: f"Safetymode: {self.controller.safety_mode.name}",
            "safetystatus": lambda _: f"Safetystatus: {self.controller.safety_mode.name}",
            "programState": self._program_state,
            "running": lambda _: f"Program running: {str(self._running()).lower()}",
            "get loaded program": lambda _: "No program loaded",
            "isProgramSaved": lambda _: "true <unnamed>",
            "stop": self._stop,
            "pause": self._pause,
            "play": self._play,
            "power on": self._power_on,
            "power off": self._power_off,
            "brake release": self._brake_release,
            "unlock protective stop": self._unlock,
            "close safety popup": lambda _: "closing safety popup",
            "close popup": lambda _: "closing popup",
            "restart safety": lambda _: "Restarting safety",
            "shutdown": lambda _: "Shutting down",
            "quit": lambda _: "Disconnected",
        }

    def partial_since(self) -> float | None:
        return self._partial_since

    def on_open(self) -> None:
        self.link.send(f"{WELCOME}\n".encode())

    def on_bytes(self, data: bytes) -> None:
        self._buffer += data
        while (end := self._buffer.find(b"\n")) >= 0:
            raw = bytes(self._buffer[:end]).rstrip(b"\r")
            del self._buffer[:end + 1]
            if len(raw) > MAX_LINE_BYTES:
                raise Refused(f"a dashboard command of {len(raw)} bytes; the twin takes at most {MAX_LINE_BYTES}")
            try:
                line = raw.decode("utf-8")
            except UnicodeDecodeError:
                log.warning("dashboard client %s: a command that is not UTF-8 was not understood", self.link.peer)
                self.link.send(b"could not understand: (not UTF-8)\n")
                continue
            reply = self._answer(line.strip())
            self.link.send(f"{reply}\n".encode())
            if line.strip() == "quit":
                self.link.close(None)
                return
        if len(self._buffer) > MAX_LINE_BYTES:
            raise Refused(f"{len(self._buffer)} bytes without a line end on the dashboard")
        self._partial_since = (self._partial_since or time.monotonic()) if self._buffer else None

    def _answer(self, line: str) -> str:
        handler = self._commands.get(line)
        if handler is not None:
            return handler(line)
        for prefix, answer in (("load ", self._load), ("popup ", lambda _: "showing popup"),
                               ("addToLog ", lambda _: "Added log message"),
                               ("setUserRole ", lambda text: f"Setting user role: {text[12:]}")):
            if line.startswith(prefix):
                return answer(line)
        shown = line if line.isprintable() else repr(line)
        log.info("dashboard client %s: not understood: %s", self.link.peer, shown[:80])
        return f"could not understand: '{shown[:200]}'"

    # --- commands -----------------------------------------------------------------------------------------
    def _running(self) -> bool:
        return self.controller.runtime_state == RuntimeState.PLAYING

    def _program_state(self, _: str) -> str:
        state = self.controller.runtime_state
        name = {RuntimeState.PLAYING: "PLAYING", RuntimeState.PAUSED: "PAUSED"}.get(state, "STOPPED")
        return f"{name} <unnamed>"

    def _load(self, line: str) -> str:
        return f"File not found: {line[5:].strip()[:200]}"

    def _stop(self, _: str) -> str:
        self.controller.stop_program("the dashboard asked (stop)")
        return "Stopped"

    def _pause(self, _: str) -> str:
        return "Pausing program" if self.controller.pause_program("the dashboard asked (pause)") else \
            "Failed to execute: pause"

    def _play(self, _: str) -> str:
        return "Starting program" if self.controller.play() else "Failed to execute: play"

    def _power_on(self, _: str) -> str:
        self.controller.power_on()
        return "Powering on"

    def _power_off(self, _: str) -> str:
        self.controller.power_off()
        return "Powering off"

    def _brake_release(self, _: str) -> str:
        self.controller.brake_release()
        return "Brake releasing"

    def _unlock(self, _: str) -> str:
        if self.controller.safety_mode != SafetyMode.PROTECTIVE_STOP:
            return "Protective stop releasing"
        left = self.controller.unlock_protective_stop()
        if left > 0:
            return ("Cannot unlock protective stop until 5s after occurrence. Always inspect cause of protective "
                    "stop before unlocking")
        return "Protective stop releasing"
