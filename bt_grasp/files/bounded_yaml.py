"""YAML parsed with bounds: the one way bt_grasp turns YAML text into data (files and ``KEY=VALUE`` values).

Safe loading stops code (no Python tags) but not two ways of exhausting the machine with a few bytes:

- **nesting**: PyYAML composes recursively, so ``[[[[...]]]]`` a few thousand deep is a ``RecursionError``;
- **aliases**: ``a: &a [x, x, x]`` then ``b: &b [*a, *a, *a]`` nine times over is 10 billion values once
  anything walks the data (a "billion laughs"); an anchor used inside itself is a cycle.

:func:`compose` composes one document, refuses nesting deeper than :data:`MAX_DEPTH` and a node graph that
expands (aliases followed) to more than :data:`MAX_VALUES` values or refers to itself, in time linear in the
file, before anything is constructed. :func:`scalar_or_text` is for one value typed on a command line or sent
by a viewer: a YAML scalar (number, boolean, text) when it is one, else the text as given.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, overload

import yaml

#: deeper than any file a person writes; PyYAML's own recursion gives out near 300 levels
MAX_DEPTH = 100
#: values (scalars, lists, mappings) a document may expand to with its aliases followed
MAX_VALUES = 1_000_000

ErrorFactory = Callable[[str, "int | None"], Exception]


def _line(node: yaml.Node | None) -> int | None:
    return node.start_mark.line + 1 if node is not None and node.start_mark is not None else None


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [part for pair in node.value for part in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def check_graph(root: yaml.Node, error: ErrorFactory) -> None:
    """Refuse a node graph deeper than :data:`MAX_DEPTH`, larger than :data:`MAX_VALUES` with aliases
    expanded, or with a cycle (each node is visited once: linear in the file's size)."""
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, finished = stack.pop()
        key = id(node)
        if finished:
            on_path.discard(key)
            kids = _children(node)
            size[key] = 1 + sum(size[id(k)] for k in kids)
            depth[key] = 1 + max((depth[id(k)] for k in kids), default=0)
            if depth[key] > MAX_DEPTH:
                raise error(f"nested deeper than {MAX_DEPTH} levels", _line(node))
            if size[key] > MAX_VALUES:
                raise error(f"expands to more than {MAX_VALUES:,} values once its aliases (*name) are followed",
                            _line(node))
            continue
        if key in size:
            continue
        if key in on_path:
            raise error("an alias (*name) refers to the collection it is in", _line(node))
        on_path.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node) if id(child) not in size)


def compose(text: str, loader: type[yaml.SafeLoader], error: ErrorFactory) -> yaml.Node | None:
    """One YAML document's node graph, checked by :func:`check_graph`; nesting too deep for the composer is
    ``error`` too. YAML syntax errors propagate as PyYAML raises them (callers word them)."""
    reader = loader(text)
    try:
        node = reader.get_single_node()
    except RecursionError:
        raise error("nested too deeply to read", None) from None
    finally:
        reader.dispose()
    if node is not None:
        check_graph(node, error)
    return node


def construct(node: yaml.Node, loader: type[yaml.SafeLoader]) -> object:
    """The Python data of a node graph :func:`compose` accepted (safe constructors only)."""
    reader = loader("")
    try:
        return reader.construct_document(node)
    finally:
        reader.dispose()


def load_value(text: str) -> object:
    """One value typed by a person (a command line's ``KEY=VALUE``, a viewer's edit) as YAML, bounded like a
    file; ``ValueError`` when it is not YAML or is nested or aliased past the limits."""
    try:
        node = compose(text, yaml.SafeLoader, lambda problem, line: ValueError(problem))
        return construct(node, yaml.SafeLoader) if node is not None else None
    except (yaml.YAMLError, RecursionError) as exc:
        raise ValueError(f"not a YAML value ({type(exc).__name__})") from None


@overload
def scalar_or_text(value: str) -> str | int | float | bool: ...


@overload
def scalar_or_text(value: str, *, keep_null: Literal[True]) -> str | int | float | bool | None: ...


def scalar_or_text(value: str, *, keep_null: bool = False) -> str | int | float | bool | None:
    """``value`` as a YAML scalar (``3`` -> 3, ``true`` -> True, ``0.5`` -> 0.5) when it is one; anything
    else (a list, a mapping, text YAML cannot parse, nesting too deep) is the text itself, and so is a YAML
    null (``null``, ``~``) unless ``keep_null``. An empty value is ``""`` (``None`` with ``keep_null``)."""
    if not value.strip():
        return None if keep_null else value
    try:
        parsed = load_value(value)
    except ValueError:
        return value
    if parsed is None and keep_null:
        return None
    return parsed if isinstance(parsed, str | int | float | bool) else value
