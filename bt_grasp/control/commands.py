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
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field

from bt_grasp.control.breakpoints import Breakpoint, parse_breakpoint
from bt_grasp.errors import BtGraspError, InputError

#: what may be written to the blackboard from a front end (as ``--set``): text is converted by the ports
BlackboardScalar = str | int | float | bool


class CommandError(BtGraspError):
    """A command a front end sent cannot be applied; the message is one sentence, the run goes on untouched."""


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
        if self.n < 1:
            raise CommandError(f"a step is at least 1 tick, got {self.n}")


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
class SetBlackboard:
    """Write entry ``key`` of the main tree's blackboard. Text is converted as the ports that read the entry
    convert a literal (``"0.12"`` for a number port); the value must fit every port that reads it."""

    key: str
    value: BlackboardScalar


@dataclass(frozen=True)
class ChooseObject:
    """Pick one object of the current detections (the list in blackboard entry ``detections``, e.g.
    ``objects`` from Perceive/PerceiveAll) by index, or by label (its colour name: the first one), and write
    it to entry ``entry`` (the one the tree acts on, e.g. ``target`` or ``object``)."""

    choice: int | str
    entry: str = "target"
    detections: str = "objects"


@dataclass(frozen=True)
class FireFault:
    """Fire a fault of the fault catalogue (``bt_grasp.faults.model.FaultKind``) now, with its parameters
    (checked as a fault plan's are)."""

    kind: str
    params: Mapping[str, object] = field(default_factory=dict)  # JSON from a front end, YAML scalars from a prompt


@dataclass(frozen=True)
class Restart:
    """End this episode and start it again with the same seed or the next (a new episode, a new log)."""

    seed: SeedPolicy = SeedPolicy.SAME


Watching = Pause | Resume | Step | SetBreakpoint | ClearBreakpoint
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
    ClearBreakpoint: "clear_breakpoint",
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
    return CommandError(f"a '{kind}' command needs '{name}' ({names}), got {value!r}")


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
        raise CommandError(f"a command is a JSON object with a 'kind', got {data!r}")
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
            return ClearBreakpoint(parse_breakpoint(spec) if spec else None)
        if kind == "set_blackboard":
            return SetBlackboard(_text(data, "key", kind), _scalar(data, "value", kind))
        if kind == "choose_object":
            return ChooseObject(_choice(data, "choice", kind), str(data.get("entry", "target")),
                                str(data.get("detections", "objects")))
        if kind == "fire_fault":
            params = data.get("params", {})
            if not isinstance(params, Mapping):
                raise CommandError(f"a 'fire_fault' command's 'params' is an object, got {params!r}")
            return FireFault(_text(data, "fault", kind), dict(params))
        if kind == "restart":
            seed = data.get("seed", "same")
            if seed not in {p.value for p in SeedPolicy}:
                raise CommandError(f"a 'restart' command's 'seed' is 'same' or 'next', got {seed!r}")
            return Restart(SeedPolicy(seed))
    except InputError as exc:  # a breakpoint spec
        raise CommandError(exc.problem) from None
    known = ", ".join([*_WATCHING_KINDS.values(), *INTERVENTION_KINDS.values()])
    raise CommandError(f"unknown command kind {kind!r}; known: {known}")
