"""Blackboard edits and object choices, checked against the ports that read the entry.

A value from a front end goes in only when every port of the tree that reads the entry accepts it (typed as
the port converts a literal: ``"0.12"`` for a number, ``true`` for a bool, one of a port's choices); a value
that does not fit raises :class:`CommandError` with one sentence and the blackboard is left as it was.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol, TypeGuard

from bt_grasp.control.commands import BlackboardScalar, CommandError
from bt_grasp.files.bounded_yaml import scalar_or_text
from bt_grasp.tree.blackboard import EMPTY, BlackboardTypeError
from bt_grasp.tree.exceptions import PortValueError, TreeRuntimeError
from bt_grasp.tree.ports import convert_text
from bt_grasp.tree.registry import PortDirection, PortSpec
from bt_grasp.tree.values import cast_to

if TYPE_CHECKING:
    from bt_grasp.tree.loader import LoadedTree
    from bt_grasp.tree.node import BtNode


class Detected(Protocol):
    """What a front end reads of a detection (``bt_grasp.perception.results.Detection``)."""

    @property
    def label(self) -> str: ...
    @property
    def centroid_base_m(self) -> tuple[float, ...]: ...
    @property
    def size_m(self) -> tuple[float, ...]: ...


def reading_ports(tree: LoadedTree, key: str) -> list[tuple[BtNode, PortSpec]]:
    """Every (node, input or inout port) of the tree that reads the main blackboard's entry ``key``
    (remapped SubTree keys included: they share the entry)."""
    entry = tree.root_blackboard.entry(key)
    if entry is None:
        return []
    found = []
    for node in tree.nodes():
        accessor = getattr(node, "ports", None)
        if accessor is None or not hasattr(accessor, "blackboard_ports"):
            continue
        for spec, blackboard, port_key in accessor.blackboard_ports():
            if spec.direction is not PortDirection.OUTPUT and blackboard.entry(port_key) is entry:
                found.append((node, spec))
    return found


#: port and entry names that name a file or folder: ``file``, ``calibration_file``, ``model_path``, ``out_dir``
_FILE_NAMES = ("file", "path", "dir", "folder")


def names_a_file(key: str, ports: Sequence[tuple[BtNode, PortSpec]]) -> bool:
    """Whether blackboard entry ``key`` names a file: its name, or the name of a port reading it, is ``file``,
    ``path``, ``dir`` or ``folder`` or ends so after an underscore (``calibration_file``). Such an entry set by
    a viewer makes the run read (or write) that file, so a front end others can reach checks where it lies
    (``bt_grasp.foxglove.control``). A plugin's port that takes a file is named so (docs/own-leaves.md)."""
    names = [key, *(spec.name for _node, spec in ports)]
    return any(n.lower() in _FILE_NAMES or n.lower().endswith(tuple("_" + w for w in _FILE_NAMES)) for n in names)


def _fit(value: BlackboardScalar, spec: PortSpec) -> object:
    if spec.type is object:
        return value
    if isinstance(value, str):
        return convert_text(value, spec)
    fitted = cast_to(value, spec.type)
    if spec.choices and fitted not in spec.choices:
        raise TreeRuntimeError(f"port '{spec.name}' must be one of {', '.join(spec.choices)}; got {value!r}")
    return fitted


def set_entry(tree: LoadedTree, key: str, value: BlackboardScalar) -> object:
    """Write ``value`` to the main blackboard's ``key`` after checking it against every port reading it;
    returns the value stored (converted by the first typed port); CommandError when it does not fit."""
    if not key or key.startswith("_"):
        raise CommandError(f"blackboard entry '{key}' cannot be set from outside (empty or private)")
    ports = reading_ports(tree, key)
    blackboard = tree.root_blackboard
    if not ports and not blackboard.has(key):
        raise CommandError(f"no port of the tree reads blackboard entry '{key}' and it holds no value; "
                           "the run goes on unchanged")
    stored: object = value
    typed = False
    for node, spec in ports:
        try:
            fitted = _fit(value, spec)
        except (TreeRuntimeError, PortValueError) as exc:
            raise CommandError(f"blackboard entry '{key}' = {value!r} does not fit {node.bt_path}'s port: "
                               f"{exc}; the run goes on unchanged") from None
        if not typed and spec.type is not object:
            stored, typed = fitted, True
    if not typed and isinstance(value, str) and not ports:
        stored = scalar_or_text(value)  # as ``--set`` reads a value: a YAML scalar, else the text
    entry = blackboard.entry(key)
    before = (entry.value, entry.declared, entry.sequence_id) if entry is not None else None
    try:
        blackboard.set(key, stored)
    except BlackboardTypeError as exc:
        if entry is not None and before is not None:
            entry.value, entry.declared, entry.sequence_id = before
        raise CommandError(f"{exc}; the run goes on unchanged") from None
    return blackboard.get(key)


def detections_in(tree: LoadedTree, entry: str) -> tuple[Detected, ...]:
    """The detections held by blackboard entry ``entry`` (a list of them, or one), () when none."""
    value = tree.root_blackboard.get(entry, None) if tree.root_blackboard.exists(entry) else None
    if value is None or value is EMPTY:
        return ()
    items: Sequence[object] = value if isinstance(value, list | tuple) else (value,)
    return tuple(v for v in items if _is_detection(v))


def _is_detection(value: object) -> TypeGuard[Detected]:
    return all(hasattr(value, a) for a in ("centroid_base_m", "size_m", "label"))


def choose_object(tree: LoadedTree, choice: int | str, entry: str, detections: str) -> tuple[int, Detected]:
    """Write the chosen detection to ``entry``; returns (its index, the detection)."""
    found = detections_in(tree, detections)
    if not found:
        raise CommandError(f"blackboard entry '{detections}' holds no detections yet; perceive first")
    if isinstance(choice, int) and not isinstance(choice, bool):
        if not 0 <= choice < len(found):
            raise CommandError(f"object {choice} is not among the {len(found)} detections (0..{len(found) - 1})")
        index = choice
    else:
        labels = [str(d.label) for d in found]
        if choice not in labels:
            raise CommandError(f"no detection labelled '{choice}'; labels: {', '.join(labels)}")
        index = labels.index(str(choice))
    ports = reading_ports(tree, entry)
    if not ports and not tree.root_blackboard.exists(entry):
        raise CommandError(f"no port of the tree reads blackboard entry '{entry}'; the run goes on unchanged")
    for node, spec in ports:
        if spec.type is not object:
            raise CommandError(f"{node.bt_path}'s port '{spec.name}' reads '{entry}' as {spec.type.__name__}, "
                               "not an object; the run goes on unchanged")
    tree.root_blackboard.set(entry, found[index])
    return index, found[index]
