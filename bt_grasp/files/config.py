"""Strict loading of the YAML files users write (scenes, calibration, fault plans, perception settings).

Files are read with ``yaml.safe_load`` semantics (no Python tags) and validated by frozen pydantic models
that forbid unknown keys. Any problem becomes one :class:`~bt_grasp.errors.ConfigError` naming the file,
the line, the key path and what was expected.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from bt_grasp.errors import ConfigError, did_you_mean
from bt_grasp.files import bounded_yaml
from bt_grasp.files.bounded_io import read_user_file

M = TypeVar("M", bound=BaseModel)


class StrictModel(BaseModel):
    """Base of every configuration model: immutable, unknown keys rejected, no type coercion from str."""

    #: no NaN or infinity anywhere (``.nan`` gravity or ``.inf`` table size passed as numbers: found by the
    #: pre-review attack)
    model_config = ConfigDict(extra="forbid", frozen=True, strict=False, validate_default=True, allow_inf_nan=False)


KeyPath = tuple[str | int, ...]


def _line_map(node: yaml.Node, path: KeyPath, out: dict[KeyPath, int]) -> None:
    out.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = key_node.value
            out[(*path, key)] = key_node.start_mark.line + 1
            _line_map(value_node, (*path, key), out)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _line_map(item, (*path, index), out)


def format_key_path(path: KeyPath) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


class _Yaml12Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 booleans: only true/false are booleans, so ``on: blue_box`` (a stack goal)
    keeps its key ``on`` instead of YAML 1.1's ``True``; ``yes``/``no``/``on``/``off`` stay text."""


_Yaml12Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


def read_yaml(path: str | Path) -> tuple[object, dict[KeyPath, int]]:
    """Parse a YAML file safely; returns the data (to check: ``validate``) and a map from key paths to line
    numbers."""
    path = Path(path)
    raw = read_user_file(path, error=ConfigError)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(path, "is not UTF-8 text") from exc
    lines: dict[KeyPath, int] = {}

    def refused(problem: str, line: int | None) -> ConfigError:
        return ConfigError(path, f"invalid YAML: {problem}", where=line)

    try:  # parsed once, bounded: nesting depth and the values its aliases expand to (bt_grasp.files.bounded_yaml)
        node = bounded_yaml.compose(text, _Yaml12Loader, refused)
        if node is not None:
            _line_map(node, (), lines)  # before constructing: merge keys (<<) flatten the node in place
        data = bounded_yaml.construct(node, _Yaml12Loader) if node is not None else None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = (exc.problem or exc.context or "malformed YAML").strip()
        if "could not determine a constructor" in problem:
            problem = "unsupported YAML tag (only plain YAML is allowed): " + problem
        raise ConfigError(path, f"invalid YAML: {problem}", where=line) from exc
    except yaml.YAMLError as exc:
        raise ConfigError(path, f"invalid YAML: {exc}") from exc
    return data, lines


def _nearest_line(path: KeyPath, lines: dict[KeyPath, int]) -> int | None:
    while True:
        if path in lines:
            return lines[path]
        if not path:
            return None
        path = path[:-1]


def validate(model: type[M], data: object, source: str | Path, lines: dict[KeyPath, int] | None = None, *,
             quote: bool = True) -> M:
    """Validate parsed data against a model; the first problem becomes a one-sentence ConfigError. ``quote=False``:
    the sentence names keys the model knows and lines, never a value or an unknown key of the file (a file named by
    someone else, whose content the sentence would show them)."""
    if data is None:
        raise ConfigError(source, "the file is empty")
    if not isinstance(data, dict):
        raise ConfigError(source, f"expected a mapping of keys at the top level, found {type(data).__name__}", 1)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        # an unknown key usually explains a "missing" one next to it (a typo): report it first
        errors = sorted(exc.errors(), key=lambda e: 0 if e["type"] == "extra_forbidden" else 1)
        err = errors[0]
        loc: KeyPath = _data_path(data, err["loc"])
        # pydantic appends the union/tag member name to loc for tagged unions; keep only real keys
        key = format_key_path(loc) or "top level"
        kind = err["type"]
        if kind == "extra_forbidden":
            parent = model
            allowed = _allowed_keys(parent, loc[:-1])
            hint = did_you_mean(str(loc[-1]), allowed) if quote else ""
            hint += f" (expected one of: {', '.join(allowed)})" if allowed else ""
            problem = f"unknown key '{loc[-1]}'{hint}" if quote else f"an unknown key{hint}"
        elif kind == "missing":
            problem = f"missing required key '{key}'"
        else:
            problem = f"{key}: {err['msg'].removeprefix('Value error, ')}"
            if quote and "input" in err and not isinstance(err["input"], dict | list):
                problem += f" (got {err['input']!r})"
        line = _nearest_line(loc, lines or {})
        raise ConfigError(source, problem, where=line) from None


def _data_path(data: object, loc: tuple[int | str, ...]) -> KeyPath:
    """The error's location as keys of the data: tagged-union member names pydantic inserts (a fixture's
    ``tray``) are not keys of the file and are dropped; the last part (an unknown or missing key) is kept."""
    path: list[str | int] = []
    node = data
    for i, part in enumerate(loc):
        if not isinstance(part, str | int):
            continue
        child = _child(node, part)
        if child is not _ABSENT:
            node = child
        elif i < len(loc) - 1 or (isinstance(node, dict) and node.get("kind") == part):
            continue  # a union member's name (a goal's or fixture's kind), not a key of the file
        path.append(part)
    return tuple(path)


_ABSENT = object()


def _child(node: object, part: int | str) -> object:
    """``node[part]`` when ``node`` is a mapping holding key ``part`` or a list with index ``part``, else
    ``_ABSENT``."""
    if isinstance(node, dict):
        return node.get(part, _ABSENT)
    if isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
        return node[part]
    return _ABSENT


def _allowed_keys(model: type[BaseModel], loc: KeyPath) -> list[str]:
    current: object = model
    for part in loc:
        if isinstance(part, int):
            continue
        field = getattr(current, "model_fields", {}).get(part)
        if field is None:
            return []
        current = _model_in(field.annotation)
        if current is None:
            return []
    return list(getattr(current, "model_fields", {}).keys())


def _model_in(annotation: object) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def load_model(model: type[M], path: str | Path) -> M:
    """Read and validate one YAML file."""
    data, lines = read_yaml(path)
    return validate(model, data, path, lines)
