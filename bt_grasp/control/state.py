"""The read-only view of a controlled run that front ends draw: frozen snapshots, safe to hand across threads."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

#: a blackboard value is shown as text cut to this many characters
VALUE_CHARS = 160


@dataclass(frozen=True)
class NodeView:
    """One node as the last tick left it: ``depth`` 0 is the root (for drawing the tree indented)."""

    path: str
    name: str
    type: str
    status: str  # IDLE, RUNNING, SUCCESS, FAILURE, SKIPPED
    depth: int


@dataclass(frozen=True)
class FailureView:
    tick: int
    leaf: str
    path: str
    reason: str | None
    message: str


@dataclass(frozen=True)
class DetectionView:
    """One object of the current detections, by its index in the list ``ChooseObject`` picks from."""

    index: int
    label: str
    centroid_base_m: tuple[float, ...]
    size_m: tuple[float, ...]


@dataclass(frozen=True)
class InterventionRecord:
    """One intervention as recorded on ``/control/interventions``: applied at the boundary after ``tick``
    (0: before the first tick), at simulated ``stamp_ns``, sent by ``source``; ``command`` is its JSON form
    (``command_to_json``, with a chosen object's index resolved and a value as stored), ``effect`` a sentence."""

    tick: int
    stamp_ns: int
    source: str
    command: dict[str, object]
    effect: str = ""

    def to_json(self) -> dict[str, object]:
        return {"tick": self.tick, "stamp_ns": self.stamp_ns, "source": self.source,
                "kind": str(self.command.get("kind", "")), "command": dict(self.command), "effect": self.effect}

    @staticmethod
    def from_json(data: Mapping[str, object]) -> InterventionRecord:
        """A recorded intervention (as ``to_json`` wrote it); KeyError or TypeError when a field it needs is
        missing or of another kind."""
        tick, command = _integer(data["tick"]), data["command"]
        if not isinstance(command, Mapping):
            raise TypeError(f"an intervention's command is an object, not {type(command).__name__}")
        return InterventionRecord(tick, _integer(data.get("stamp_ns", 0)), str(data.get("source", "")),
                                  dict(command), str(data.get("effect", "")))


def _integer(value: object) -> int:
    """``int(value)`` of a number or a numeral (ValueError or TypeError as ``int`` raises them)."""
    if not isinstance(value, int | float | str):
        raise TypeError(f"int() argument must be a string or a real number, not '{type(value).__name__}'")
    return int(value)


@dataclass(frozen=True)
class RunState:
    """What a front end shows. ``tick``: the last tick finished (0 before the first); ``paused``: the run
    holds (at a tick boundary, or before a node when ``pause_reason`` says so); ``finished``: the run ended;
    ``message``: the answer to the last command (a rejected value's sentence)."""

    tick: int = 0
    sim_time_s: float = 0.0
    paused: bool = False
    pause_reason: str = ""
    finished: bool = False
    nodes: tuple[NodeView, ...] = ()
    blackboard: tuple[tuple[str, str], ...] = ()
    last_failure: FailureView | None = None
    detections: tuple[DetectionView, ...] = ()
    breakpoints: tuple[str, ...] = ()
    interventions: tuple[InterventionRecord, ...] = ()
    message: str = ""
    tree_status: str = "IDLE"
    settings: tuple[str, ...] = field(default_factory=tuple)  # entries a port reads: what may be set
    #: the settings that name a file (``bt_grasp.control.edits.names_a_file``): a viewer may set them only to a
    #: file under the folder the run's user named (``--control-files``)
    file_settings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def break_on_failure(self) -> bool:
        return "fail" in self.breakpoints


def value_text(value: object) -> str:
    text = " ".join((repr(value) if not isinstance(value, str) else value).split())  # one line
    return text if len(text) <= VALUE_CHARS else text[: VALUE_CHARS - 3] + "..."
