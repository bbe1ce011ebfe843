"""RTDE on port 30004 (UR's RTDE guide, protocol version 2): setup, start/pause and data packages.

Per connection: one output recipe at a time (a new setup replaces it) sent at the requested frequency, which
must divide into the controller's period (the controller sends every ``round(rate / frequency)``-th cycle), and
up to 255 input recipes (ids from 1 per connection, as ur_rtde's fixed recipe numbers expect). An input field
written by one connection is ``IN_USE`` for the others until that connection closes. Inputs take effect at the
next controller cycle; the latest value written before a cycle is the one it sees, as on a controller.
"""

from __future__ import annotations

import logging
import struct
import threading
import time
from dataclasses import dataclass

from bt_grasp.sim.twin.netio import Link, Refused, Session
from bt_grasp.sim.twin.outputs import compile_recipe
from bt_grasp.sim.twin.rtde_types import (
    HEADER,
    IN_USE,
    INPUT_FIELDS,
    MAX_PACKAGE_BYTES,
    NOT_FOUND,
    OUTPUT_FIELDS,
    PROTOCOL_VERSION,
    MessageLevel,
    PackageType,
    Recipe,
    package,
    parse_names,
    text_message,
)
from bt_grasp.sim.twin.state import ControllerState, InputBank

log = logging.getLogger(__name__)

MAX_INPUT_RECIPES = 255
MAX_FIELDS_PER_RECIPE = 2000


@dataclass(frozen=True)
class ControllerVersion:
    major: int
    minor: int
    bugfix: int
    build: int

    def __str__(self) -> str:
        return f"{self.major}.{self.minor}.{self.bugfix}.{self.build}"


class RtdeHub:
    """The state every RTDE connection shares: input claims, the input bank, the controller's version and rate."""

    def __init__(self, version: ControllerVersion, rate_hz: float, inputs: InputBank) -> None:
        self.version = version
        self.rate_hz = rate_hz
        self.inputs = inputs
        self._lock = threading.Lock()
        self._claims: dict[str, RtdeSession] = {}
        self._sessions: list[RtdeSession] = []

    def make_session(self, link: Link) -> RtdeSession:
        session = RtdeSession(link, self)
        with self._lock:
            self._sessions.append(session)
        return session

    def forget(self, session: RtdeSession) -> None:
        with self._lock:
            if session in self._sessions:
                self._sessions.remove(session)
            for name in [n for n, owner in self._claims.items() if owner is session]:
                del self._claims[name]

    def claim(self, session: RtdeSession, names: list[str]) -> list[str]:
        """The setup reply's types for an input recipe of ``names``, claiming them for ``session`` if all are
        free and known."""
        with self._lock:
            types = []
            for name in names:
                field_type = INPUT_FIELDS.get(name)
                owner = self._claims.get(name)
                if field_type is None:
                    types.append(NOT_FOUND)
                elif owner is not None and owner is not session:
                    types.append(IN_USE)
                else:
                    types.append(field_type.wire_name)
            if NOT_FOUND not in types and IN_USE not in types:
                for name in names:
                    self._claims[name] = session
            return types

    def publish(self, cycle: int, state: ControllerState) -> None:
        """Send this cycle's data package to every started connection whose frequency falls on ``cycle``."""
        with self._lock:
            sessions = list(self._sessions)
        for session in sessions:
            session.publish(cycle, state)


class RtdeSession(Session):
    def __init__(self, link: Link, hub: RtdeHub) -> None:
        super().__init__(link)
        self.hub = hub
        self._buffer = bytearray()
        self._partial_since: float | None = None
        self._output: Recipe | None = None
        self._output_values = None
        self._output_every = 1
        self._inputs: dict[int, Recipe] = {}
        self._next_input_id = 1
        self._next_output_id = 1
        self.started = False
        self.packages_sent = 0

    # --- the loop's hooks ---------------------------------------------------------------------------
    def partial_since(self) -> float | None:
        return self._partial_since

    def on_close(self) -> None:
        self.started = False
        self.hub.forget(self)

    def on_bytes(self, data: bytes) -> None:
        self._buffer += data
        while len(self._buffer) >= HEADER.size:
            size, kind = HEADER.unpack_from(self._buffer)
            if size < HEADER.size or size > MAX_PACKAGE_BYTES:
                raise Refused(f"an RTDE package of {size} bytes (type {kind}); the twin takes 3 to "
                              f"{MAX_PACKAGE_BYTES} bytes")
            if len(self._buffer) < size:
                break
            payload = bytes(self._buffer[HEADER.size:size])
            del self._buffer[:size]
            self._handle(kind, payload)
        if self._buffer:
            self._partial_since = self._partial_since or time.monotonic()
        else:
            self._partial_since = None

    # --- packages -----------------------------------------------------------------------------------
    def _reply(self, kind: PackageType, payload: bytes = b"") -> None:
        self.link.send(package(kind, payload))

    def _warn(self, sentence: str) -> None:
        """One logged sentence for a refused package, also sent to the client as an RTDE error message."""
        log.warning("RTDE client %s: %s", self.link.peer, sentence)
        self.link.send(text_message(sentence, "twin", MessageLevel.ERROR))

    def _handle(self, kind: int, payload: bytes) -> None:
        if kind == PackageType.REQUEST_PROTOCOL_VERSION:
            version = struct.unpack(">H", payload)[0] if len(payload) == 2 else -1
            accepted = version == PROTOCOL_VERSION
            if not accepted:
                log.warning("RTDE client %s asked for protocol version %s; the twin speaks version %d",
                            self.link.peer, version, PROTOCOL_VERSION)
            self._reply(PackageType.REQUEST_PROTOCOL_VERSION, bytes([int(accepted)]))
        elif kind == PackageType.GET_URCONTROL_VERSION:
            v = self.hub.version
            self._reply(PackageType.GET_URCONTROL_VERSION, struct.pack(">IIII", v.major, v.minor, v.bugfix, v.build))
        elif kind == PackageType.TEXT_MESSAGE:
            self._client_text(payload)
        elif kind == PackageType.CONTROL_PACKAGE_SETUP_OUTPUTS:
            self._setup_outputs(payload)
        elif kind == PackageType.CONTROL_PACKAGE_SETUP_INPUTS:
            self._setup_inputs(payload)
        elif kind == PackageType.CONTROL_PACKAGE_START:
            self.started = self._output is not None
            if not self.started:
                log.warning("RTDE client %s asked to start with no output recipe; refused (the guide requires at "
                            "least one output)", self.link.peer)
            self._reply(PackageType.CONTROL_PACKAGE_START, bytes([int(self.started)]))
        elif kind == PackageType.CONTROL_PACKAGE_PAUSE:
            self.started = False
            self._reply(PackageType.CONTROL_PACKAGE_PAUSE, b"\x01")
        elif kind == PackageType.DATA_PACKAGE:
            self._data(payload)
        else:
            self._warn(f"an RTDE package of unknown type {kind} ({len(payload)} bytes) was ignored")

    def _client_text(self, payload: bytes) -> None:
        try:
            n = payload[0]
            message = payload[1:1 + n].decode("utf-8", "replace")
            m = payload[1 + n]
            source = payload[2 + n:2 + n + m].decode("utf-8", "replace")
        except IndexError:
            self._warn("a text message that does not follow the protocol version 2 layout was ignored")
            return
        log.info("RTDE text message from %s (%s): %s", self.link.peer, (source.isprintable() and source) or "?",
                 message if message.isprintable() else repr(message))

    def _setup_outputs(self, payload: bytes) -> None:
        if len(payload) < 8:
            self._warn("an output setup without its frequency was refused")
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x00")
            return
        frequency = struct.unpack(">d", payload[:8])[0]
        try:
            names = parse_names(payload[8:])
        except ValueError as exc:
            self._warn(f"an output setup was refused: {exc}")
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x00")
            return
        types = [OUTPUT_FIELDS[n].wire_name if n in OUTPUT_FIELDS else NOT_FOUND for n in names]
        rate = self.hub.rate_hz
        problem = None
        if self.started:
            problem = "synchronisation is running (pause first)"
        elif not names or len(names) > MAX_FIELDS_PER_RECIPE:
            problem = f"it names {len(names)} fields"
        elif not (frequency == frequency and 0.0 < frequency <= rate):  # NaN fails the first test
            problem = f"its frequency {frequency:g} Hz is not within (0, {rate:g}] Hz"
        elif NOT_FOUND in types:
            missing = [n for n, t in zip(names, types, strict=True) if t == NOT_FOUND]
            problem = f"the controller has no output named {', '.join(missing[:5])}"
        if problem is not None:
            log.warning("RTDE client %s: output recipe refused: %s", self.link.peer, problem)
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x00" + ",".join(types).encode())
            return
        recipe = Recipe(self._next_output_id, tuple(names), tuple(OUTPUT_FIELDS[n] for n in names))
        self._next_output_id = self._next_output_id % 255 + 1
        self._output = recipe
        self._output_values = compile_recipe(recipe.names)  # type: ignore[assignment]
        self._output_every = max(1, round(rate / frequency))
        log.info("RTDE client %s: output recipe %d, %d fields at %g Hz", self.link.peer, recipe.recipe_id,
                 len(names), rate / self._output_every)
        log.debug("RTDE client %s: output fields: %s", self.link.peer, ", ".join(names))
        self._reply(PackageType.CONTROL_PACKAGE_SETUP_OUTPUTS, bytes([recipe.recipe_id]) + ",".join(types).encode())

    def _setup_inputs(self, payload: bytes) -> None:
        try:
            names = parse_names(payload)
        except ValueError as exc:
            self._warn(f"an input setup was refused: {exc}")
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_INPUTS, b"\x00")
            return
        if not names or len(names) > MAX_FIELDS_PER_RECIPE or len(self._inputs) >= MAX_INPUT_RECIPES:
            self._warn(f"an input setup of {len(names)} fields (recipe {len(self._inputs) + 1}) was refused")
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_INPUTS, b"\x00")
            return
        types = self.hub.claim(self, names)
        if NOT_FOUND in types or IN_USE in types:
            bad = [f"{n} ({t})" for n, t in zip(names, types, strict=True) if t in (NOT_FOUND, IN_USE)]
            log.warning("RTDE client %s: input recipe refused: %s", self.link.peer, ", ".join(bad[:5]))
            self._reply(PackageType.CONTROL_PACKAGE_SETUP_INPUTS, b"\x00" + ",".join(types).encode())
            return
        recipe = Recipe(self._next_input_id, tuple(names), tuple(INPUT_FIELDS[n] for n in names))
        log.debug("RTDE client %s: input recipe %d: %s", self.link.peer, self._next_input_id, ", ".join(names))
        self._inputs[recipe.recipe_id] = recipe
        self._next_input_id += 1
        self._reply(PackageType.CONTROL_PACKAGE_SETUP_INPUTS, bytes([recipe.recipe_id]) + ",".join(types).encode())

    def _data(self, payload: bytes) -> None:
        recipe = self._inputs.get(payload[0]) if payload else None
        if recipe is None:
            self._warn(f"a data package for input recipe {payload[0] if payload else '?'}, which this connection "
                       "has not set up, was ignored")
            return
        try:
            values = recipe.unpack(payload)
        except (ValueError, struct.error) as exc:
            self._warn(f"a data package was ignored: {exc}")
            return
        self.hub.inputs.write(recipe.names, values)

    # --- outputs (the controller thread) --------------------------------------------------------------
    def publish(self, cycle: int, state: ControllerState) -> None:
        recipe, values = self._output, self._output_values
        if not self.started or recipe is None or values is None or cycle % self._output_every:
            return
        if self.link.send(recipe.pack(values(state))):
            self.packages_sent += 1
