"""The commands a front end sends to a running episode: typed, frozen, each with a JSON form.

Two families:

* **watching** commands change what the operator sees, never the run: :class:`Pause`, :class:`Resume`,
  :class:`Step`, :class:`SetBreakpoint`, :class:`ClearBreakpoint`. They are not recorded: a paused run is
  the same run.
* **interventions** change the run: :class:`SetBlackboard`, :class:`ChooseObject`, :class:`FireFault`,
  :class:`Stop`, :class:`Restart`. Each takes effect at a tick boundary and is recorded on
  ``/control/interventions`` with that tick and its source, so ``replay --resim`` applies it again there.

``command_to_json`` / ``command_from_json`` give every intervention a JSON form (the log's and the Foxglove
front end's); ``command_from_json`` raises :class:`CommandError` with one sentence on a malformed command.

**One validation.** Every command checks its own fields when it is made (``__post_init__``), so no path into the
controller (a Foxglove parameter, a ``/control/command`` message, the terminal, a recorded intervention) can
carry a command the others would refuse: numbers are finite, text is at most :data:`MAX_TEXT_CHARS` characters,
a fault's parameters are a small JSON object, and a breakpoint set holds at most :data:`MAX_BREAKPOINTS`.
:func:`command_from_json_text` reads a message: at most :data:`MAX_MESSAGE_BYTES`, JSON without ``NaN`` or
``Infinity`` (which Python's reader takes by default).
"""

from __future__ import annotations

import enum
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from bt_grasp.control.breakpoints import MAX_BREAKPOINTS, Breakpoint, parse_breakpoint
from bt_grasp.errors import BtGraspError, InputError

#: what may be written to the blackboard from a front end (as ``--set``): text is converted by the ports
BlackboardScalar = str | int | float | bool

#: the longest text a command carries (a blackboard value, a key, a label, a fault kind)
MAX_TEXT_CHARS = 4096
#: the largest command message a front end may send (a JSON command is a few hundred bytes)
MAX_MESSAGE_BYTES = 64 << 10
#: a fault's parameters: at most this many values, nested at most this deep
MAX_PARAM_VALUES = 64
MAX_PARAM_DEPTH = 4
#: the most ticks one step command asks for (a re-simulation's tick limit)
MAX_STEP_TICKS = 10_000_000


class CommandError(BtGraspError):
    """A command a front end sent cannot be applied; the message is one sentence, the run goes on untouched."""


def _check_text(value: str, what: str) -> None:
    if len(value) > MAX_TEXT_CHARS:
        raise CommandError(f"{what} is {len(value)} characters, more than the {MAX_TEXT_CHARS} a command carries")


def _check_scalar(value: object, what: str) -> None:
    """A blackboard value: text (bounded), an integer of at most 64 bits, a finite number or a boolean."""
    if isinstance(value, bool):
        return
    if isinstance(value, float) and not math.isfinite(value):
        raise CommandError(f"{what} must be a finite number, got {value}")
    if isinstance(value, int) and not -(2**63) <= value < 2**63:
        raise CommandError(f"{what} must be an integer of at most 64 bits")
    if isinstance(value, str):
        _check_text(value, what)


def _check_params(value: object, what: str, depth: int = 0, budget: list[int] | None = None) -> None:
    """A fault's parameters: JSON values (objects with text keys, lists, text, finite numbers, booleans, null),
    at most :data:`MAX_PARAM_VALUES` of them, nested at most :data:`MAX_PARAM_DEPTH` deep."""
    budget = [MAX_PARAM_VALUES] if budget is None else budget
    budget[0] -= 1
    if budget[0] < 0 or depth > MAX_PARAM_DEPTH:
        raise CommandError(f"{what} are more than {MAX_PARAM_VALUES} values or nested more than "
                           f"{MAX_PARAM_DEPTH} deep")
    if isinstance(value, Mapping):
        for key, item in value.items():
            if not isinstance(key, str):
                raise CommandError(f"{what} have a key that is not text")
            _check_text(key, what)
            _check_params(item, what, depth + 1, budget)
    elif isinstance(value, list | tuple):
        for item in value:
            _check_params(item, what, depth + 1, budget)
    elif value is not None and not isinstance(value, str | int | float | bool):
        raise CommandError(f"{what} hold a {type(value).__name__}, not a JSON value")
    else:
        _check_scalar(value, what)


class Source(enum.StrEnum):
    """Who sent a command: recorded with every intervention."""

    TERMINAL = "terminal"
    FOXGLOVE = "foxglove"
    API = "api"  # a notebook, a test, a script
    RESIM = "resim"  # ``replay --resim`` applying a recorded intervention again


class SeedPolicy(enum.StrEnum):
    """Restart with the same seed (the same episode again) or the next one."""

    SAME = "same"
    NEXT = "next"


@dataclass(frozen=True)
class Pause:
    """Hold the run at the next tick boundary (simulated time stops)."""


@dataclass(frozen=True)
class Resume:
    """Let a paused run go on."""


@dataclass(frozen=True)
class Step:
    """Run ``n`` ticks (``n >= 1``), then pause."""

    n: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.n, bool) or not isinstance(self.n, int):
            raise CommandError(f"a step is a whole number of ticks, got {self.n!r}")
        if self.n < 1:
            raise CommandError(f"a step is at least 1 tick, got {self.n}")
        if self.n > MAX_STEP_TICKS:
            raise CommandError(f"a step is at most {MAX_STEP_TICKS:,} ticks, got {self.n}")


@dataclass(frozen=True)
class Stop:
    """End the run at the next tick boundary; the log is finished and the run judged as it stands."""


@dataclass(frozen=True)
class SetBreakpoint:
    breakpoint: Breakpoint


@dataclass(frozen=True)
class ClearBreakpoint:
    """Remove one breakpoint (None: every breakpoint)."""

    breakpoint: Breakpoint | None = None


@dataclass(frozen=True)
class SetBreakpoints:
    """Replace the whole set of breakpoints by these (at most :data:`MAX_BREAKPOINTS`): applied to the set the
    controller holds when it takes the command, never compared with a view a front end saw earlier."""

    breakpoints: tuple[Breakpoint, ...] = ()

    def __post_init__(self) -> None:
        if len(self.breakpoints) > MAX_BREAKPOINTS:
            raise CommandError(f"a run holds at most {MAX_BREAKPOINTS} breakpoints, got {len(self.breakpoints)}")


@dataclass(frozen=True)
class SetBlackboard:
    """Write entry ``key`` of the main tree's blackboard. Text is converted as the ports that read the entry
    convert a literal (``"0.12"`` for a number port); the value must fit every port that reads it."""

    key: str
    value: BlackboardScalar

    def __post_init__(self) -> None:
        if not isinstance(self.key, str):
            raise CommandError(f"a blackboard entry is named by text, got {self.key!r}")
        _check_text(self.key, "a blackboard entry's name")
        if not isinstance(self.value, str | int | float | bool):
            raise CommandError("a blackboard entry takes text, a number or true/false, got "
                               f"{type(self.value).__name__}")
        _check_scalar(self.value, "a blackboard value")


@dataclass(frozen=True)
class ChooseObject:
    """Pick one object of the current detections (the list in blackboard entry ``detections``, e.g.
    ``objects`` from Perceive/PerceiveAll) by index, or by label (its colour name: the first one), and write
    it to entry ``entry`` (the one the tree acts on, e.g. ``target`` or ``object``)."""

    choice: int | str
    entry: str = "target"
    detections: str = "objects"

    def __post_init__(self) -> None:
        if isinstance(self.choice, bool) or not isinstance(self.choice, int | str):
            raise CommandError(f"an object is chosen by its index or its label, got {self.choice!r}")
        _check_scalar(self.choice, "an object's index or label")
        for what, text in (("entry", self.entry), ("detections", self.detections)):
            if not isinstance(text, str):
                raise CommandError(f"a choice's '{what}' is an entry's name, got {text!r}")
            _check_text(text, f"a choice's '{what}'")


@dataclass(frozen=True)
class FireFault:
    """Fire a fault of the fault catalogue (``bt_grasp.faults.model.FaultKind``) now, with its parameters
    (checked as a fault plan's are)."""

    kind: str
    params: Mapping[str, object] = field(default_factory=dict)  # JSON from a front end, YAML scalars from a prompt

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str):
            raise CommandError(f"a fault is named by its kind, got {self.kind!r}")
        _check_text(self.kind, "a fault's kind")
        if not isinstance(self.params, Mapping):
            raise CommandError(f"a fault's params are an object, got {type(self.params).__name__}")
        _check_params(self.params, "a fault's params")


@dataclass(frozen=True)
class Restart:
    """End this episode and start it again with the same seed or the next (a new episode, a new log)."""

    seed: SeedPolicy = SeedPolicy.SAME


Watching = Pause | Resume | Step | SetBreakpoint | ClearBreakpoint | SetBreakpoints
Intervention = SetBlackboard | ChooseObject | FireFault | Stop | Restart
Command = Watching | Intervention

#: the ``kind`` of each intervention in its JSON form
INTERVENTION_KINDS: dict[type, str] = {
    SetBlackboard: "set_blackboard",
    ChooseObject: "choose_object",
    FireFault: "fire_fault",
    Stop: "stop",
    Restart: "restart",
}
_WATCHING_KINDS: dict[type, str] = {
    Pause: "pause", Resume: "resume", Step: "step", SetBreakpoint: "set_breakpoint",
    ClearBreakpoint: "clear_breakpoint", SetBreakpoints: "set_breakpoints",
}


def is_intervention(command: Command) -> bool:
    return type(command) in INTERVENTION_KINDS


def command_to_json(command: Command) -> dict[str, object]:
    """The command as a JSON object: ``{"kind": ..., <fields>}`` (a fault's parameters as given)."""
    kind = INTERVENTION_KINDS.get(type(command)) or _WATCHING_KINDS[type(command)]
    out: dict[str, object] = {"kind": kind}
    if isinstance(command, Step):
        out["n"] = command.n
    elif isinstance(command, SetBreakpoint):
        out["breakpoint"] = command.breakpoint.spec
    elif isinstance(command, ClearBreakpoint):
        out["breakpoint"] = command.breakpoint.spec if command.breakpoint is not None else ""
    elif isinstance(command, SetBreakpoints):
        out["breakpoints"] = [bp.spec for bp in command.breakpoints]
    elif isinstance(command, SetBlackboard):
        out.update(key=command.key, value=command.value)
    elif isinstance(command, ChooseObject):
        out.update(choice=command.choice, entry=command.entry, detections=command.detections)
    elif isinstance(command, FireFault):
        out.update(fault=command.kind, params=dict(command.params))
    elif isinstance(command, Restart):
        out["seed"] = command.seed.value
    return out


def _refused(kind: str, name: str, types: tuple[type, ...], value: object) -> CommandError:
    names = " or ".join(t.__name__ for t in types)
    return CommandError(f"a '{kind}' command needs '{name}' ({names}), got {_short(value)}")


def _text(data: Mapping[str, object], name: str, kind: str) -> str:
    value = data.get(name)
    if not isinstance(value, str):
        raise _refused(kind, name, (str,), value)
    return value


def _whole(data: Mapping[str, object], name: str, kind: str) -> int:
    value = data.get(name)
    if not isinstance(value, int) or isinstance(value, bool):
        raise _refused(kind, name, (int,), value)
    return value


def _scalar(data: Mapping[str, object], name: str, kind: str) -> BlackboardScalar:
    value = data.get(name)
    if not isinstance(value, str | int | float | bool):
        raise _refused(kind, name, (str, int, float, bool), value)
    return value


def _choice(data: Mapping[str, object], name: str, kind: str) -> int | str:
    value = data.get(name)
    if not isinstance(value, int | str) or isinstance(value, bool):
        raise _refused(kind, name, (int, str), value)
    return value


def command_from_json(data: object) -> Command:
    """A command from its JSON form (a front end's message, a recorded intervention)."""
    if not isinstance(data, Mapping):
        raise CommandError(f"a command is a JSON object with a 'kind', got {_short(data)}")
    kind = data.get("kind")
    try:
        if kind == "pause":
            return Pause()
        if kind == "resume":
            return Resume()
        if kind == "stop":
            return Stop()
        if kind == "step":
            return Step(_whole(data, "n", kind) if "n" in data else 1)
        if kind == "set_breakpoint":
            return SetBreakpoint(parse_breakpoint(_text(data, "breakpoint", kind)))
        if kind == "clear_breakpoint":
            spec = data.get("breakpoint") or ""
            if not isinstance(spec, str):
                raise CommandError(f"a 'clear_breakpoint' command's 'breakpoint' is a spec, got {_short(spec)}")
            return ClearBreakpoint(parse_breakpoint(spec) if spec else None)
        if kind == "set_breakpoints":
            return SetBreakpoints(parse_breakpoint_list(data.get("breakpoints")))
        if kind == "set_blackboard":
            return SetBlackboard(_text(data, "key", kind), _scalar(data, "value", kind))
        if kind == "choose_object":
            return ChooseObject(_choice(data, "choice", kind), str(data.get("entry", "target")),
                                str(data.get("detections", "objects")))
        if kind == "fire_fault":
            params = data.get("params", {})
            if not isinstance(params, Mapping):
                raise CommandError(f"a 'fire_fault' command's 'params' is an object, got {_short(params)}")
            return FireFault(_text(data, "fault", kind), dict(params))
        if kind == "restart":
            seed = data.get("seed", "same")
            if seed not in {p.value for p in SeedPolicy}:
                raise CommandError(f"a 'restart' command's 'seed' is 'same' or 'next', got {_short(seed)}")
            return Restart(SeedPolicy(seed))
    except InputError as exc:  # a breakpoint spec
        raise CommandError(exc.problem) from None
    known = ", ".join([*_WATCHING_KINDS.values(), *INTERVENTION_KINDS.values()])
    raise CommandError(f"unknown command kind {_short(kind)}; known: {known}")


def parse_breakpoint_list(value: object, source: str = "breakpoints") -> tuple[Breakpoint, ...]:
    """A list of breakpoint specs (at most :data:`MAX_BREAKPOINTS`, each a spec) as breakpoints, duplicates
    dropped; :class:`CommandError` naming the first problem. The list's length is checked before any spec."""
    if not isinstance(value, list | tuple) or not all(isinstance(v, str) for v in value):
        raise CommandError(f"breakpoints are a list of specs such as [\"fail\", \"tick:40\"], got "
                           f"{_short(value, as_json=True)}")
    if len(value) > MAX_BREAKPOINTS:
        raise CommandError(f"a run holds at most {MAX_BREAKPOINTS} breakpoints, got {len(value)}")
    try:
        return tuple(dict.fromkeys(parse_breakpoint(spec, source) for spec in value))
    except InputError as exc:
        raise CommandError(exc.problem) from None


class MessageError(CommandError):
    """A front end's message is not a readable JSON command at all (too large, not JSON, NaN or Infinity)."""


def _refuse_constant(name: str) -> float:
    raise MessageError(f"holds {name}: numbers must be finite")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise MessageError(f"holds {text[:40]}, which is no finite number: numbers must be finite")
    return value


def command_from_json_text(data: bytes) -> Command:
    """A command from a front end's message (UTF-8 JSON, at most :data:`MAX_MESSAGE_BYTES`, no NaN or Infinity):
    :class:`MessageError` when it is no readable JSON command ("this one ..."), :class:`CommandError` when the
    command is malformed."""
    if len(data) > MAX_MESSAGE_BYTES:
        raise MessageError(f"cannot be read ({len(data)} bytes, more than the {MAX_MESSAGE_BYTES} a command may be)")
    try:
        value = json.loads(data.decode("utf-8"), parse_constant=_refuse_constant, parse_float=_finite_float)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise MessageError(f"is not JSON ({exc})") from None
    except MessageError:
        raise
    except (ValueError, RecursionError) as exc:  # an integer of 5,000 digits; nesting past Python's stack
        raise MessageError(f"cannot be read ({type(exc).__name__})") from None
    return command_from_json(value)


def _short(value: object, *, as_json: bool = False) -> str:
    """A value a front end sent, quoted in a sentence (as Python or, ``as_json``, as JSON writes it): at most 60
    characters of it."""
    try:
        if as_json:
            text = json.dumps(value) if isinstance(value, list | dict | str) or value is None else str(value)
        else:
            text = repr(value)
    except (ValueError, RecursionError, TypeError):
        text = type(value).__name__
    return text if len(text) <= 60 else text[:57] + "..."
