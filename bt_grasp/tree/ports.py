"""Port values: literals typed at load time, ``{key}`` blackboard references resolved at tick time."""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from bt_grasp.tree.blackboard import EMPTY, Blackboard
from bt_grasp.tree.exceptions import PortValueError, TreeRuntimeError
from bt_grasp.tree.registry import NO_DEFAULT, PortDirection, PortSpec, is_text_port_type
from bt_grasp.tree.values import cast_to, int_prefix, real_prefix

logger = logging.getLogger(__name__)

_TRUE = ("true", "True", "TRUE", "1")
_FALSE = ("false", "False", "FALSE", "0")
_TYPE_NAMES = {str: "text", int: "an integer", float: "a number", bool: "true or false", object: "any value"}


def convert_text(text: str, port: PortSpec, where: str = "") -> Any:
    """Convert a literal as written in a tree file to the port's type (BT.CPP ``convertFromString``: numbers
    are read from the start of the text, as ``std::from_chars`` does, with no leading space or ``+``; what
    follows a number is ignored, with a logged warning when it is more than spaces; a bool is ``true``,
    ``false``, ``1``, ``0`` or their ``True``/``TRUE`` forms exactly). ``where`` (``file:line``) starts the
    warning's text."""
    kind = port.type
    value: Any
    if kind is str or kind is object:
        value = text
    elif is_text_port_type(kind):
        try:
            value = kind.from_port_text(text)  # type: ignore[attr-defined]
        except ValueError as exc:
            raise PortValueError(f"port '{port.name}': {exc}") from None
    elif kind is bool:
        if text in _TRUE:
            value = True
        elif text in _FALSE:
            value = False
        else:
            raise PortValueError(f"port '{port.name}' needs true or false, got {text!r}")
    else:
        found = int_prefix(text) if kind is int else real_prefix(text)
        if found is None:
            raise PortValueError(f"port '{port.name}' needs {_TYPE_NAMES[kind]}, got {text!r}")
        value, rest = found
        if rest.strip():
            logger.warning(
                "%sport '%s': %r is read as %r, as BT.CPP reads it (%r is ignored)",
                f"{where}: " if where else "", port.name, text, value, rest,
            )
    if port.choices and value not in port.choices:
        raise PortValueError(f"port '{port.name}' must be one of {', '.join(port.choices)}; got {text!r}")
    return value


def blackboard_key(text: str, port_name: str) -> str | None:
    """The key of a blackboard reference (``{key}``, ``{=}`` meaning the port's own name), else None."""
    stripped = text.strip()
    if stripped in ("{=}", "="):
        return port_name
    if len(stripped) >= 3 and stripped[0] == "{" and stripped[-1] == "}":
        return stripped[1:-1].strip()
    if len(stripped) >= 4 and stripped.startswith("${") and stripped[-1] == "}":
        return stripped[2:-1].strip()
    return None


@dataclass(frozen=True)
class PortValue:
    """A resolved port: either a typed ``literal`` or a blackboard ``key``."""

    port: PortSpec
    literal: Any = NO_DEFAULT
    key: str | None = None

    @staticmethod
    def from_text(port: PortSpec, text: str, where: str = "") -> PortValue:
        key = blackboard_key(text, port.name)
        if key is not None:
            if not key:
                raise PortValueError(f"port '{port.name}' has an empty blackboard reference {text!r}")
            return PortValue(port, key=key)
        if port.direction is PortDirection.OUTPUT:
            raise PortValueError(
                f"output port '{port.name}' needs a blackboard key such as {{{port.name}}}, got {text!r}"
            )
        return PortValue(port, literal=convert_text(text, port, where))

    @staticmethod
    def from_default(port: PortSpec) -> PortValue:
        if isinstance(port.default, str):
            return PortValue.from_text(port, port.default)
        return PortValue(port, literal=port.default)


class PortAccessor:
    """A node's ports: ``get`` reads (literal or blackboard), ``set`` writes an output port."""

    __slots__ = ("_blackboard", "_owner", "_specs", "_values")

    def __init__(
        self,
        specs: Mapping[str, PortSpec],
        values: Mapping[str, PortValue],
        blackboard: Blackboard,
        owner: str,
    ) -> None:
        self._specs = dict(specs)
        self._values = dict(values)
        self._blackboard = blackboard
        self._owner = owner

    def _value(self, name: str) -> PortValue:
        value = self._values.get(name)
        if value is None:
            if name not in self._specs:
                raise TreeRuntimeError(f"{self._owner}: node has no port '{name}'")
            raise TreeRuntimeError(f"{self._owner}: port '{name}' was not set in the tree file")
        return value

    def has(self, name: str) -> bool:
        """True when the port was given (or has a default). For an input port naming an entry, that entry
        must also hold a value; an output port only needs to be connected to a key."""
        value = self._values.get(name)
        if value is None:
            return False
        if value.key is None or value.port.direction is PortDirection.OUTPUT:
            return True
        return self._blackboard.has(value.key)

    def key(self, name: str) -> str | None:
        """The blackboard key a port points to, None for a literal."""
        return self._value(name).key

    def get(self, name: str) -> Any:
        """The port's value: the typed literal, or the blackboard entry converted to the port's type as
        BT.CPP's ``getInput<T>`` does (text parsed; a real becomes an integer only without a fraction, an
        integer a bool only when 0 or 1; a number read by a text port renders as BT.CPP prints it)."""
        value = self._value(name)
        if value.key is None:
            return value.literal
        entry = self._blackboard.entry(value.key)
        if entry is None or entry.value is EMPTY:
            raise TreeRuntimeError(
                f"{self._owner}: port '{name}' reads blackboard entry '{value.key}', which has no value yet"
            )
        try:
            return cast_to(entry.value, value.port.type)
        except TreeRuntimeError as exc:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' (blackboard entry '{value.key}'): {exc}") from None

    def set(self, name: str, value: Any) -> bool:
        """Write an output (or inout) port's blackboard entry; True when written. An output port the tree does
        not connect is left alone and False returned, as BT.CPP's ``setOutput`` returns an error value that
        nodes are free to ignore (Nav2's leaves write ``error_code_id`` whether the tree reads it or not)."""
        if name not in self._values and name in self._specs and self._specs[name].direction is PortDirection.OUTPUT:
            return False
        port_value = self._value(name)
        if port_value.port.direction is PortDirection.INPUT:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' is an input port; it cannot be written")
        if port_value.key is None:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' is a literal, not a blackboard key")
        self._blackboard.set(port_value.key, value)
        return True

    def names(self) -> tuple[str, ...]:
        return tuple(self._values)

    def blackboard_ports(self) -> tuple[tuple[PortSpec, Blackboard, str], ...]:
        """Every port bound to a blackboard key: (spec, the node's blackboard, key), for tools that check
        a value against the ports reading an entry (``bt_grasp.control``)."""
        return tuple((v.port, self._blackboard, v.key) for v in self._values.values() if v.key is not None)


class EntryWatch:
    """Tells whether one blackboard entry was written since the last look (BT.CPP compares the entry's
    ``sequence_id`` with the one it saw last; WasEntryUpdated, SkipUnlessUpdated, WaitValueUpdate).

    ``text`` is the ``entry`` attribute as written: ``{key}`` or a plain key.
    """

    def __init__(self, text: str) -> None:
        self.key = blackboard_key(text, "entry") or text
        self.seen = 0

    def written_since(self, blackboard: Blackboard) -> bool:
        """True when the entry exists and its write count changed since the previous call."""
        entry = blackboard.entry(self.key)
        if entry is None:
            return False
        previous, self.seen = self.seen, entry.sequence_id
        return previous != entry.sequence_id
