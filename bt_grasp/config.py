"""Strict loading of the YAML files users write (scenes, calibration, fault plans, perception settings).

Files are read with ``yaml.safe_load`` semantics (no Python tags) and validated by frozen pydantic models
that forbid unknown keys. Any problem becomes one :class:`~bt_grasp.errors.ConfigError` naming the file,
the line, the key path and what was expected.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from bt_grasp.errors import ConfigError

M = TypeVar("M", bound=BaseModel)


class StrictModel(BaseModel):
    """Base of every configuration model: immutable, unknown keys rejected, no type coercion from str."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=False, validate_default=True)


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


def read_yaml(path: str | Path) -> tuple[Any, dict[KeyPath, int]]:
    """Parse a YAML file safely; returns the data and a map from key paths to line numbers."""
    path = Path(path)
    if not path.exists():
        raise ConfigError(path, "no such file")
    if path.is_dir():
        raise ConfigError(path, "is a folder, not a YAML file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(path, "is not UTF-8 text") from exc
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = (exc.problem or exc.context or "malformed YAML").strip()
        if "could not determine a constructor" in problem:
            problem = "unsupported YAML tag (only plain YAML is allowed): " + problem
        raise ConfigError(path, f"invalid YAML: {problem}", where=line) from exc
    except yaml.YAMLError as exc:
        raise ConfigError(path, f"invalid YAML: {exc}") from exc
    lines: dict[KeyPath, int] = {}
    if node is not None:
        _line_map(node, (), lines)
    return data, lines


def _nearest_line(path: KeyPath, lines: dict[KeyPath, int]) -> int | None:
    while True:
        if path in lines:
            return lines[path]
        if not path:
            return None
        path = path[:-1]


def validate(model: type[M], data: Any, source: str | Path, lines: dict[KeyPath, int] | None = None) -> M:
    """Validate parsed data against a model; the first problem becomes a one-sentence ConfigError."""
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
        loc: KeyPath = tuple(p for p in err["loc"] if isinstance(p, str | int))
        # pydantic appends the union/tag member name to loc for tagged unions; keep only real keys
        key = format_key_path(loc) or "top level"
        kind = err["type"]
        if kind == "extra_forbidden":
            parent = model
            allowed = _allowed_keys(parent, loc[:-1])
            close = difflib.get_close_matches(str(loc[-1]), allowed, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            hint += f" (expected one of: {', '.join(allowed)})" if allowed else ""
            problem = f"unknown key '{loc[-1]}'{hint}"
        elif kind == "missing":
            problem = f"missing required key '{key}'"
        else:
            problem = f"{key}: {err['msg']}"
            if "input" in err and not isinstance(err["input"], dict | list):
                problem += f" (got {err['input']!r})"
        line = _nearest_line(loc, lines or {})
        raise ConfigError(source, problem, where=line) from None


def _allowed_keys(model: type[BaseModel], loc: KeyPath) -> list[str]:
    current: Any = model
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


def _model_in(annotation: Any) -> type[BaseModel] | None:
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
