"""Port values: literals typed at load time, ``{key}`` blackboard references resolved at tick time, and what a
node reads and writes through them (:class:`PortAccessor`, a node's ``self.ports``)."""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TypeVar, overload

from bt_grasp.tree.blackboard import EMPTY, Blackboard
from bt_grasp.tree.exceptions import PortValueError, TreeRuntimeError
from bt_grasp.tree.registry import NO_DEFAULT, PortDirection, PortSpec, is_text_port_type
from bt_grasp.tree.values import cast_to, int_prefix, real_prefix

logger = logging.getLogger(__name__)

T = TypeVar("T")

_TRUE = ("true", "True", "TRUE", "1")
_FALSE = ("false", "False", "FALSE", "0")
_TYPE_NAMES = {str: "text", int: "an integer", float: "a number", bool: "true or false", object: "any value"}


def convert_text(text: str, port: PortSpec, where: str = "") -> object:
    """Convert a literal as written in a tree file to the port's type (BT.CPP ``convertFromString``: numbers
    are read from the start of the text, as ``std::from_chars`` does, with no leading space or ``+``; what
    follows a number is ignored, with a logged warning when it is more than spaces; a bool is ``true``,
    ``false``, ``1``, ``0`` or their ``True``/``TRUE`` forms exactly). ``where`` (``file:line``) starts the
    warning's text. A type that cannot be read from text refuses every literal."""
    kind = port.type
    value: object
    if kind is str or kind is object:
        value = text
    elif is_text_port_type(kind):
        try:
            value = getattr(kind, "from_port_text")(text)  # noqa: B009 - is_text_port_type checked it
        except ValueError as exc:
            raise PortValueError(f"port '{port.name}': {exc}") from None
    elif kind is bool:
        if text in _TRUE:
            value = True
        elif text in _FALSE:
            value = False
        else:
            raise PortValueError(f"port '{port.name}' needs true or false, got {text!r}")
    elif kind is int or kind is float:
        found = int_prefix(text) if kind is int else real_prefix(text)
        if found is None:
            raise PortValueError(f"port '{port.name}' needs {_TYPE_NAMES[kind]}, got {text!r}")
        value, rest = found
        if rest.strip():
            logger.warning(
                "%sport '%s': %r is read as %r, as BT.CPP reads it (%r is ignored)",
                f"{where}: " if where else "", port.name, text, value, rest,
            )
    else:
        raise PortValueError(f"port '{port.name}': a {kind.__name__} cannot be written in a tree file (it has no "
                             f"from_port_text); give a blackboard entry such as {{{port.name}}}")
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
    literal: object = NO_DEFAULT
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
    """A node's ports (``self.ports``), read and written as BT.CPP's ``getInput``/``setOutput`` do.

    * ``get(name)`` / ``get(name, int)``: the value, or None when the port has none (the tree did not give it and
      it has no default, or its blackboard entry was never written): BT.CPP's ``getInput`` returns that case to
      the node, which tests it. A value of a type the port cannot take is an error (exit 2), not None.
    * ``require(name)`` / ``require(name, int)``: the strict form: the value, or an error naming the tree file's
      line, the node and the port (exit 2).
    * ``has(name)``: ``get`` would return a value (an output port: the tree connects it).
    * ``set(name, value)``: write an output port's entry (False when the tree leaves it unconnected).
    """

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

    def _spec(self, name: str) -> PortSpec:
        spec = self._specs.get(name)
        if spec is None:
            raise TreeRuntimeError(f"{self._owner}: node has no port '{name}'")
        return spec

    def has(self, name: str) -> bool:
        """True when the port has a value now: a literal or default, or a blackboard entry that holds one. An output
        port only needs to be connected to a key. False for a name the node does not declare."""
        value = self._values.get(name)
        if value is None:
            return False
        if value.key is None or value.port.direction is PortDirection.OUTPUT:
            return True
        return self._blackboard.has(value.key)

    def key(self, name: str) -> str | None:
        """The blackboard key a port points to; None for a literal or a port the tree did not give."""
        self._spec(name)
        value = self._values.get(name)
        return value.key if value is not None else None

    @overload
    def get(self, name: str) -> object | None: ...

    @overload
    def get(self, name: str, kind: type[T]) -> T | None: ...

    def get(self, name: str, kind: type[object] | None = None) -> object | None:
        """BT.CPP's ``getInput<T>``: the port's value converted to ``kind`` (the port's declared type when not
        given), or None when it has none. Text is parsed as BT.CPP's ``convertFromString`` does; a real becomes
        an integer only without a fraction, an integer a bool only when 0 or 1; a value that cannot be converted
        is an error (exit 2)."""
        return self._read(name, kind)

    @overload
    def require(self, name: str) -> object: ...

    @overload
    def require(self, name: str, kind: type[T]) -> T: ...

    def require(self, name: str, kind: type[object] | None = None) -> object:
        """The strict form of :meth:`get` (BT.CPP's ``getInput`` followed by a throw when it failed): the value,
        or an error (exit 2) naming the tree file's line, the node and the port that has none."""
        found = self._read(name, kind)
        if found is not None:
            return found
        value = self._values.get(name)
        if value is None or value.key is None:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' was not given in the tree file and has no default")
        raise TreeRuntimeError(f"{self._owner}: port '{name}' reads blackboard entry '{value.key}', which has no "
                               "value yet")

    def _read(self, name: str, kind: type[object] | None) -> object | None:
        spec = self._spec(name)
        value = self._values.get(name)
        if value is None:
            return None
        wanted = kind if kind is not None else spec.type
        try:
            if value.key is None:  # a literal, converted at load time
                raw, where = value.literal, "its value"
                converted = raw if isinstance(raw, wanted) else cast_to(raw, wanted)
            else:
                entry = self._blackboard.entry(value.key)
                if entry is None or entry.value is EMPTY:
                    return None
                raw, where = entry.value, f"blackboard entry '{value.key}'"
                converted = cast_to(raw, wanted)
        except TreeRuntimeError as exc:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' ({where}): {exc}") from None
        if not isinstance(converted, wanted):
            raise TreeRuntimeError(f"{self._owner}: port '{name}' ({where}) holds a {type(converted).__name__}, "
                                   f"not a {wanted.__name__}")
        return converted

    def set(self, name: str, value: object) -> bool:
        """Write an output (or inout) port's blackboard entry; True when written. An output port the tree does
        not connect is left alone and False returned, as BT.CPP's ``setOutput`` returns an error value that
        nodes are free to ignore (Nav2's leaves write ``error_code_id`` whether the tree reads it or not)."""
        spec = self._spec(name)
        if spec.direction is PortDirection.INPUT:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' is an input port; it cannot be written")
        port_value = self._values.get(name)
        if port_value is None:
            return False
        if port_value.key is None:
            raise TreeRuntimeError(f"{self._owner}: port '{name}' is a literal, not a blackboard key")
        self._blackboard.set(port_value.key, value)
        return True

    def names(self) -> tuple[str, ...]:
        """The ports the tree gave (or that have defaults)."""
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
