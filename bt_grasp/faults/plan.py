"""Loading a fault plan: a strict YAML file and/or ``--inject`` strings -> one frozen :class:`FaultPlan`."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.errors import ConfigError, InputError
from bt_grasp.faults.model import PARAMS, FaultEntry, FaultKind, FaultPlanFile
from bt_grasp.faults.syntax import parse_inject
from bt_grasp.files.config import KeyPath, StrictModel, read_yaml, validate
from bt_grasp.files.json_types import JsonObject

log = logging.getLogger(__name__)

INJECT_SOURCE = "--inject"


@dataclass(frozen=True)
class Trigger:
    """When a fault arms. Exactly one of: ``at_tick``; ``on_leaf`` (+ ``nth``); ``probability`` (+ ``on_leaf``)."""

    at_tick: int | None = None
    on_leaf: str | None = None
    nth: int | None = None
    probability: float | None = None

    def describe(self) -> str:
        if self.at_tick is not None:
            return f"tick:{self.at_tick}"
        if self.probability is not None:
            return f"{self.on_leaf or '*'}~{self.probability:g}"
        return f"{self.on_leaf}#{self.nth or 1}"

    def to_dict(self) -> JsonObject:
        return {k: v for k, v in self.__dict__.items() if v is not None}


@dataclass(frozen=True)
class Fault:
    """One validated fault: ``params`` is the kind's parameter model (see :data:`model.PARAMS`)."""

    kind: FaultKind
    trigger: Trigger
    count: int
    params: StrictModel  # the kind's model (model.PARAMS[kind]): read it with ArmedFault.params_as
    label: str
    source: str  # the plan file or "--inject"
    where: str  # "faults[2]" or the inject string

    def to_dict(self) -> JsonObject:
        return {
            "kind": self.kind.value,
            "label": self.label,
            "trigger": self.trigger.to_dict(),
            "count": self.count,
            "params": self.params.model_dump(),
        }


@dataclass(frozen=True)
class FaultPlan:
    faults: tuple[Fault, ...]
    source: str | None = None

    def __len__(self) -> int:
        return len(self.faults)


def _sub_lines(lines: dict[KeyPath, int], prefix: KeyPath) -> dict[KeyPath, int]:
    n = len(prefix)
    return {path[n:]: line for path, line in lines.items() if path[:n] == prefix}


def _build(entry: FaultEntry, index: int, source: str, lines: dict[KeyPath, int], where: str) -> Fault:
    model = PARAMS[entry.kind]
    key: KeyPath = ("faults", index, "params")
    raw = entry.params or {}
    try:
        params = validate(model, raw, source, _sub_lines(lines, key))
    except ConfigError as exc:
        line = exc.where if exc.where.startswith("line ") else lines.get(key, lines.get(key[:2]))
        problem = _tidy(exc.problem.removeprefix("top level: "))
        raise ConfigError(source, f"faults[{index}].params ({entry.kind.value}): {problem}", line) from None
    trigger = Trigger(
        at_tick=entry.at_tick,
        on_leaf=entry.on_leaf,
        nth=(entry.nth or 1) if entry.on_leaf is not None and entry.probability is None else None,
        probability=entry.probability,
    )
    label = entry.name or f"{entry.kind.value}@{trigger.describe()}"
    return Fault(entry.kind, trigger, entry.count, params, label, source, where)


def _tidy(problem: str) -> str:
    return problem.replace("Value error, ", "")


def _from_file(path: Path) -> list[Fault]:
    data, lines = read_yaml(path)
    try:
        parsed = validate(FaultPlanFile, data, path, lines)
    except ConfigError as exc:
        raise ConfigError(exc.source, _tidy(exc.problem), exc.where or None) from None
    return [_build(e, i, str(path), lines, f"faults[{i}]") for i, e in enumerate(parsed.faults)]


def _from_inject(text: str) -> Fault:
    data = parse_inject(text)
    try:
        entry = validate(FaultEntry, data, INJECT_SOURCE)
        return _build(entry, 0, INJECT_SOURCE, {}, text)
    except ConfigError as exc:
        problem = _tidy(exc.problem.removeprefix("faults[0]."))
        raise InputError(INJECT_SOURCE, f"'{text}': {problem}") from None


def fault_now(kind: str, params: Mapping[str, object], tick: int, source: str) -> Fault:
    """A fault an operator fires by hand after ``tick`` (``bt_grasp.control.FireFault``), checked as a plan's
    fault is; InputError naming ``source`` and the problem in one sentence."""
    where = f"{kind} now"
    try:
        entry = validate(FaultEntry, {"kind": kind, "at_tick": max(int(tick), 1), "params": dict(params)}, source)
        return _build(entry, 0, source, {}, where)
    except ConfigError as exc:
        problem = _tidy(exc.problem.removeprefix("top level: ").removeprefix("faults[0]."))
        raise InputError(source, f"fault '{kind}': {problem}") from None


def load_fault_plan(path: Path | None, inject: Sequence[str] = ()) -> FaultPlan:
    """The faults of a plan file (if any) followed by those of the ``--inject`` strings, in order.

    Raises ConfigError (file:line: problem) for a bad file and InputError("--inject", ...) for a bad string.
    """
    faults: list[Fault] = []
    if path is not None:
        faults.extend(_from_file(Path(path)))
    faults.extend(_from_inject(text) for text in inject)
    if not faults:
        raise InputError(INJECT_SOURCE, "no fault plan file and no --inject string were given")
    log.debug("fault plan: %s", ", ".join(f.label for f in faults))
    return FaultPlan(tuple(faults), str(path) if path is not None else None)
