"""The Foxglove front end of an interactive run: parameters and a published command topic mapped to the control API.

A live run started with ``bt-grasp run ... --live --control`` serves, besides its topics, the Foxglove WebSocket
protocol's *parameters* (Studio's stock **Parameters** panel lists and edits them) and takes client-published
JSON messages on :data:`COMMAND_TOPIC` (Studio's stock **Publish** panel sends them). Both become the typed
commands of :mod:`bt_grasp.control` and go through the same :class:`~bt_grasp.control.Controller` as the
terminal UI's keys, so an intervention from Foxglove is recorded and re-simulated like any other (source
``foxglove``).

========================  ==========================================================================================
parameter                 meaning (writable unless marked *read*)
========================  ==========================================================================================
``run.paused``            ``true`` pauses at the next tick boundary, ``false`` resumes
``run.step``              ``N`` (>= 1) runs N ticks, then pauses; reads 0
``run.stop``              ``true`` ends the run (the log is finished, the run judged as it stands); reads false
``run.restart``           ``"same"`` or ``"next"``: ends this episode and starts it again with the same seed or the
                          next (a new episode, a new log); reads ""
``run.tick``              *read*: the last tick finished (0: before the first)
``run.sim_time_s``        *read*: simulated time
``run.status``            *read*: ``running``, ``paused: <why>`` or ``finished``
``run.message``           *read*: the answer to the last command (a refusal's sentence)
``run.last_failure``      *read*: the last leaf FAILURE (tick, leaf path, reason)
``breakpoints``           the breakpoints as a list of specs (``["fail", "tick:40", "node:Lift"]``); the list
                          written replaces the set (``[]`` clears every one)
``bb.<key>``              a blackboard entry a port reads as text, a number or a bool (``lift_height``, ``color``)
``detections``            *read*: the current detections, ``"<index>: <label> at (x, y, z) m"``
``choose.object``         an index or a label of the detections: written to entry ``target`` (configurable)
``fault.fire``            a fault kind of the catalogue (``"frame_drop"``), or ``{"fault": KIND, "params": {...}}``
``fault.kinds``           *read*: the catalogue's kinds, comma-separated
========================  ==========================================================================================

A message on :data:`COMMAND_TOPIC` is a command's JSON form (:func:`bt_grasp.control.command_from_json`:
``{"kind": "pause"}``, ``{"kind": "step", "n": 5}``, ``{"kind": "set_blackboard", "key": ..., "value": ...}``).

Every value is checked before anything is sent, by the commands' one validation (:mod:`bt_grasp.control.commands`:
finite numbers, bounded text and lists, at most 100 breakpoints, messages of at most 64 KiB): a bad one gets one
sentence back (the live server sends it as a status message: Studio lists it under Problems) and the run goes on
untouched. The ``breakpoints`` parameter replaces the set the controller holds when it takes it (one command),
never a difference from a view the viewer saw earlier. A refusal only the tick loop can
find (a value no port reading the entry accepts, an object index past the detections) comes back the same way
once the controller has answered.

Security: the Foxglove WebSocket protocol has no authentication, and the SDK's server does not say where a
client connects from. Control is therefore accepted only when the live server listens on a loopback address
(only this machine's viewers can reach it); on any other host it is refused unless ``allow_remote`` (the run
command's ``--allow-remote-control``, which prints a warning). Any user of the machine can reach a loopback
port, so a setting that names a file (``bb.calibration_file``: the run would read it as the run's user) is
accepted from a viewer only when it lies under the folder the run's user named with ``--control-files DIR``
(``control_files``; none by default), symbolic links resolved, and the refusal is the same sentence whether the
file exists or not. Nothing here imports the simulator or the
WebSocket server: :class:`bt_grasp.foxglove.live.LiveServer` carries the values to and from the protocol.
"""

from __future__ import annotations

import json
import logging
import math
import os
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.control.commands import (
    ChooseObject,
    Command,
    CommandError,
    FireFault,
    MessageError,
    Pause,
    Restart,
    Resume,
    SeedPolicy,
    SetBlackboard,
    SetBreakpoints,
    Source,
    Step,
    Stop,
    command_from_json_text,
    parse_breakpoint_list,
)
from bt_grasp.control.controller import Controller
from bt_grasp.control.state import RunState
from bt_grasp.faults.model import FaultKind
from bt_grasp.files.hosts import is_loopback
from bt_grasp.files.json_types import JsonValue
from bt_grasp.foxglove.layout import COMMAND_SCHEMA as COMMAND_SCHEMA  # the command topic, named where its
from bt_grasp.foxglove.layout import COMMAND_TOPIC as COMMAND_TOPIC  # Publish panels are; and here, as before

log = logging.getLogger(__name__)

#: the prefix of the parameters that are blackboard entries
BB_PREFIX = "bb."

#: a parameter value as the run publishes it (what a client sets may be any value the protocol carries)
ParamValue = bool | int | float | str | list[str]

#: the most parameters one request may set (the control layout sets one at a time)
MAX_PARAMETERS = 64

READ_ONLY = ("run.tick", "run.sim_time_s", "run.status", "run.message", "run.last_failure", "detections",
             "fault.kinds")

#: the sentences of a controller that are no refusal: an intervention applied ("tick 12: lift_height = 0.12"), a
#: breakpoint set or cleared, an intervention sent while the run holds inside a tick (before a node)
_APPLIED_PREFIXES = ("tick ", "breakpoint ", "breakpoints ")
_WAITING = " waits for the end of tick "


def is_refusal(message: str) -> bool:
    """Whether a controller's answer (``RunState.message``) refuses a command: every other answer says what was
    applied or that it waits for the tick boundary."""
    return bool(message) and not message.startswith(_APPLIED_PREFIXES) and _WAITING not in message


def fault_kinds() -> tuple[str, ...]:
    return tuple(k.value for k in FaultKind)


@dataclass(frozen=True)
class Answer:
    """What one request from a client did: the commands sent and, when refused, one sentence per problem."""

    sent: tuple[Command, ...] = ()
    problems: tuple[str, ...] = ()


class FoxgloveControl:
    """Foxglove parameters and command messages in, the control API's commands out; the run's state as
    parameters back. Thread-safe: the live server calls it from its own threads, the controller's listener
    from the tick loop's.

    Args:
        controller: the run's controller (commands are sent to it with source ``foxglove``).
        host: the address the live server listens on (control only on a loopback one...).
        allow_remote: ...unless this is set.
        choose_entry: the blackboard entry ``choose.object`` writes (the one the tree acts on).
        detections_entry: the entry holding the detections it chooses from.
        control_files: the folder a setting that names a file may point into (``--control-files``); None: no
            file may be named from a viewer.
    """

    def __init__(self, controller: Controller, *, host: str = "127.0.0.1", allow_remote: bool = False,
                 choose_entry: str = "target", detections_entry: str = "objects",
                 control_files: Path | None = None) -> None:
        self._controller = controller
        self.host = host
        self.enabled = allow_remote or is_loopback(host)
        self.control_files = control_files
        self._choose_entry = choose_entry
        self._detections_entry = detections_entry
        self._kinds = fault_kinds()
        self._lock = threading.Lock()
        self._published: dict[str, ParamValue] = {}
        self._last_message = ""
        self._on_change: Callable[[dict[str, ParamValue]], None] | None = None
        self._on_refusal: Callable[[str], None] | None = None

    @property
    def refusal(self) -> str:
        """Why control is off ('' when on)."""
        if self.enabled:
            return ""
        return (f"this run takes no control from Foxglove: its live server listens on {self.host}, which other "
                "machines can reach, and the protocol has no authentication (start it with a loopback "
                "--live-host, or --allow-remote-control)")

    # ---- run state -> parameters ------------------------------------------------------------------------------
    def parameters(self, names: Sequence[str] = ()) -> dict[str, ParamValue]:
        """The parameters as the run stands (``names``: only those; empty: all)."""
        values = state_parameters(self._controller.state(), self._kinds)
        return values if not names else {n: values[n] for n in names if n in values}

    def watch(self, on_change: Callable[[dict[str, ParamValue]], None], on_refusal: Callable[[str], None]) -> None:
        """Call ``on_change(changed parameters)`` and ``on_refusal(sentence)`` as the run's view changes
        (from the tick loop's thread: both must only queue)."""
        self._on_change, self._on_refusal = on_change, on_refusal
        self._controller.subscribe(self._state_changed)

    def _state_changed(self, state: RunState) -> None:
        values = state_parameters(state, self._kinds)
        with self._lock:
            changed = {k: v for k, v in values.items() if self._published.get(k) != v}
            self._published = values
            message, fresh = state.message, state.message != self._last_message
            self._last_message = message
        if changed and self._on_change is not None:
            self._on_change(changed)
        if fresh and is_refusal(message) and self._on_refusal is not None:
            self._on_refusal(message)

    # ---- parameters -> commands -------------------------------------------------------------------------------
    def set_parameters(self, values: Mapping[str, object]) -> Answer:
        """Map the values a client set to commands and send them; a refused value sends nothing."""
        if not self.enabled:
            return Answer(problems=(self.refusal,))
        if len(values) > MAX_PARAMETERS:
            return Answer(problems=(f"a request sets at most {MAX_PARAMETERS} parameters, this one {len(values)}",))
        state = self._controller.state()
        sent: list[Command] = []
        problems: list[str] = []
        for name, value in values.items():
            shown_name = name if len(name) <= 100 else name[:97] + "..."
            try:
                commands = parameter_commands(name, value, state, self._kinds, self._choose_entry,
                                              self._detections_entry)
                for command in commands:
                    self._check_files(command, state)
            except CommandError as exc:
                problems.append(f"parameter {shown_name!r}: {exc}")
                continue
            for command in commands:
                self._controller.send(command, Source.FOXGLOVE)
            sent.extend(commands)
        for problem in problems:
            log.info("foxglove control refused: %s", problem)
        return Answer(tuple(sent), tuple(problems))

    def command_message(self, data: bytes) -> Answer:
        """One JSON message a client published on :data:`COMMAND_TOPIC`."""
        if not self.enabled:
            return Answer(problems=(self.refusal,))
        try:
            command = command_from_json_text(data)
            self._check_files(command, self._controller.state())
        except MessageError as exc:
            return Answer(problems=(f"a message on {COMMAND_TOPIC} is a JSON command, and this one {exc}",))
        except CommandError as exc:
            return Answer(problems=(f"a message on {COMMAND_TOPIC}: {exc}",))
        self._controller.send(command, Source.FOXGLOVE)
        return Answer((command,))

    def _check_files(self, command: Command, state: RunState) -> None:
        """A blackboard edit of a setting that names a file: the file must lie under :attr:`control_files`
        (see the module's Security paragraph); the sentence is the same whether the file exists or not."""
        if not isinstance(command, SetBlackboard) or command.key not in state.file_settings:
            return
        if self.control_files is None:
            raise CommandError(f"'{command.key}' names a file, and this run takes no file names from a viewer "
                               "(start it with --control-files DIR to allow files under DIR)")
        folder = Path(os.path.realpath(self.control_files))
        given = os.path.join(os.getcwd(), str(command.value))
        if not _under(os.path.normpath(given), folder) or not _under(os.path.realpath(given), folder):
            raise CommandError(f"'{command.key}' names a file, and a file named from a viewer must lie under "
                               f"{self.control_files} (--control-files); {str(command.value)[:200]!r} is not under "
                               "it")


def _under(path: str, folder: Path) -> bool:
    """Whether ``path`` is ``folder`` or lies below it (as text: the caller resolves links when it should)."""
    candidate = Path(path)
    return candidate == folder or folder in candidate.parents


def state_parameters(state: RunState, kinds: Sequence[str]) -> dict[str, ParamValue]:
    """The run's view as parameter values (see the module's table)."""
    if state.finished:
        status = "finished"
    elif state.paused:
        status = f"paused: {state.pause_reason}" if state.pause_reason else "paused"
    else:
        status = "running"
    failure = state.last_failure
    values: dict[str, ParamValue] = {
        "run.paused": state.paused,
        "run.step": 0,
        "run.stop": False,
        "run.restart": "",
        "run.tick": state.tick,
        "run.sim_time_s": round(state.sim_time_s, 6),
        "run.status": status,
        "run.message": state.message,
        "run.last_failure": "" if failure is None else
        f"tick {failure.tick}: {failure.path} {failure.reason or 'FAILURE'}: {failure.message}",
        "breakpoints": list(state.breakpoints),
        "detections": [f"{d.index}: {d.label} at ({', '.join(f'{x:.3f}' for x in d.centroid_base_m)}) m"
                       for d in state.detections],
        "choose.object": "",
        "fault.fire": "",
        "fault.kinds": ", ".join(kinds),
    }
    shown = dict(state.blackboard)
    for key in state.settings:
        values[BB_PREFIX + key] = _shown_value(shown.get(key, ""))
    return values


def _shown_value(text: str) -> ParamValue:
    """A blackboard entry's text as the value an editor shows: a number or bool as such, else the text."""
    if text in ("True", "False"):
        return text == "True"
    try:
        number = float(text)
    except ValueError:
        return text
    if not math.isfinite(number):
        return text
    return int(number) if text.lstrip("-").isdigit() else number


def parameter_commands(name: str, value: object, state: RunState, kinds: Sequence[str],
                       choose_entry: str = "target", detections_entry: str = "objects") -> list[Command]:
    """The commands one parameter's new value means; CommandError (one sentence) when it means none."""
    if name == "run.paused":
        return [Pause() if _bool(value) else Resume()]
    if name == "run.step":
        if value in (0, None, ""):
            return []  # the read-back value, set again by an editor
        n = _int(value)
        if n < 1:
            raise CommandError(f"a step is at least 1 tick, got {n}")
        return [Step(n)]
    if name == "run.stop":
        return [Stop()] if _bool(value) else []
    if name == "run.restart":
        if value in ("", None):
            return []
        if value not in {p.value for p in SeedPolicy}:
            raise CommandError(f'it takes "same" or "next" (the seed of the new episode), got {_shown(value)}')
        return [Restart(SeedPolicy(value))]
    if name == "breakpoints":
        return [SetBreakpoints(parse_breakpoint_list(value))]
    if name.startswith(BB_PREFIX):
        key = name[len(BB_PREFIX):]
        if key not in state.settings:
            known = ", ".join(state.settings) or "none"
            raise CommandError(f"blackboard entry '{key[:100]}' is no setting of this tree (settings: {known})")
        if not isinstance(value, str | int | float | bool):
            raise CommandError(f"a blackboard entry takes text, a number or true/false, got {_shown(value)}")
        return [SetBlackboard(key, value)]
    if name == "choose.object":
        if value in ("", None):
            return []
        if isinstance(value, bool) or not isinstance(value, int | str):
            raise CommandError(f"an object is chosen by its index or its label, got {_shown(value)}")
        return [ChooseObject(value, choose_entry, detections_entry)]
    if name == "fault.fire":
        return _fault_commands(value, kinds)
    if name in READ_ONLY:
        raise CommandError("it shows the run and cannot be set")
    raise CommandError("this run has no such parameter")


def _bool(value: object) -> bool:
    if not isinstance(value, bool):
        raise CommandError(f"it takes true or false, got {_shown(value)}")
    return value


def _int(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int | float) or (
            isinstance(value, float) and not math.isfinite(value)) or value != int(value):
        raise CommandError(f"it takes a whole number of ticks, got {_shown(value)}")
    return int(value)


def _shown(value: object) -> str:
    """A value a viewer sent, quoted in a sentence: JSON, at most 60 characters of it."""
    try:
        text = json.dumps(value) if isinstance(value, list | dict | str) or value is None else str(value)
    except (ValueError, RecursionError):
        text = type(value).__name__
    return text if len(text) <= 60 else text[:57] + "..."


def _fault_commands(value: object, kinds: Sequence[str]) -> list[Command]:
    if value in ("", None):
        return []
    params: dict[str, JsonValue] = {}
    if isinstance(value, dict):
        kind, given = value.get("fault"), value.get("params", {})
        extra = sorted(set(value) - {"fault", "params"})
        if extra:
            raise CommandError(f"a fault is {{\"fault\": KIND, \"params\": {{...}}}}; unknown field '{extra[0]}'")
        if not isinstance(given, dict):
            raise CommandError(f"a fault's params are an object, got {_shown(given)}")
        params = given
    else:
        kind = value
    if not isinstance(kind, str) or kind not in kinds:
        raise CommandError(f"{_shown(kind)} is no fault of the catalogue; kinds: {', '.join(kinds)}")
    return [FireFault(kind, dict(params))]
