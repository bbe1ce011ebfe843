"""Scoped blackboards with BehaviorTree.CPP v4 semantics (not py_trees' process-global Blackboard).

Every ``<BehaviorTree>`` instance (the main tree and each ``<SubTree>``) owns one :class:`Blackboard`.
A SubTree's blackboard reaches its parent's entries only through remapping:

* ``<SubTree ID="X" port="{parent_key}"/>``: key ``port`` inside X *is* entry ``parent_key`` outside;
* ``port="literal"``: X gets its own entry ``port`` holding the string ``literal``;
* ``_autoremap="true"``: every key not found inside is looked up (or created) in the parent under the same
  name, except private keys starting with ``_``;
* a key starting with ``@`` always means the root blackboard (``@battery``).

Entries are shared objects, so a remapped key and the parent's key see the same value.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Final

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.values import convert_text, copy_into


class _Empty:
    def __repr__(self) -> str:
        return "<empty>"


#: the value of an entry that was declared (a port points to it) but never written
EMPTY: Final = _Empty()


#: the scalar types an entry can be declared with (BT.CPP's strongly typed entries)
_SCALARS = (bool, int, float, str)


class BlackboardTypeError(TreeRuntimeError):
    """A value or a port does not fit the type an entry was declared with (BT.CPP's "once declared, the
    type of a port shall not change")."""


class Entry:
    """One blackboard value; shared between blackboards that remap to it.

    ``declared`` is the scalar type the entry was declared with (by a typed port of the tree, or by the
    first value a node wrote), None while any value may go in (entries a script created: BT.CPP's
    ``AnyTypeAllowed``). ``sequence_id`` counts the writes (``WasEntryUpdated`` reads it).
    """

    __slots__ = ("declared", "sequence_id", "value")

    def __init__(self, value: object = EMPTY, declared: type | None = None) -> None:
        self.value = value
        self.sequence_id = 0
        self.declared = declared


def scalar_type(value: object) -> type | None:
    """``bool``, ``int``, ``float`` or ``str`` for a scalar value, None for anything else."""
    for kind in _SCALARS:
        if isinstance(value, kind):
            return kind
    return None


def is_private(key: str) -> bool:
    return key.startswith("_")


class Blackboard:
    """A scoped blackboard. ``parent`` is the blackboard of the enclosing tree (None for the root)."""

    def __init__(self, parent: Blackboard | None = None, *, autoremap: bool = False) -> None:
        self._storage: dict[str, Entry] = {}
        self._parent = parent
        self._remap: dict[str, str] = {}
        self.autoremap = autoremap

    @property
    def parent(self) -> Blackboard | None:
        return self._parent

    @property
    def root(self) -> Blackboard:
        bb = self
        while bb._parent is not None:
            bb = bb._parent
        return bb

    def add_remapping(self, internal: str, external: str) -> None:
        """Make ``internal`` (a key inside this tree) an alias of ``external`` in the parent."""
        self._remap[internal] = external

    @property
    def remappings(self) -> dict[str, str]:
        return dict(self._remap)

    # ---- entries -------------------------------------------------------------------------------
    def entry(self, key: str) -> Entry | None:
        """The entry ``key`` resolves to, following remapping; None when there is none."""
        if key.startswith("@"):
            return self.root._storage.get(key[1:])
        found = self._storage.get(key)
        if found is not None:
            return found
        parent = self._parent
        if parent is not None:
            external = self._remap.get(key)
            if external is not None:
                return parent.entry(external)
            if self.autoremap and not is_private(key):
                return parent.entry(key)
        return None

    def create_entry(self, key: str) -> Entry:
        """The entry for ``key``, created where remapping says it lives when it does not exist yet."""
        if key.startswith("@"):
            return self.root.create_entry(key[1:])
        found = self._storage.get(key)
        if found is not None:
            return found
        parent = self._parent
        external = self._remap.get(key)
        if parent is not None and external is not None:
            entry = parent.create_entry(external)
        elif parent is not None and self.autoremap and not is_private(key):
            entry = parent.create_entry(key)
        else:
            entry = Entry()
        self._storage[key] = entry
        return entry

    def declare(self, key: str, kind: type | None = None) -> None:
        """Create an empty entry (BT.CPP creates one for every ``{key}`` port when it builds a tree) declared
        with the port's type: a scalar or an application class (BT.CPP's strongly typed ports; ``object``
        declares nothing). A second port of another type raises BlackboardTypeError, except on an entry
        declared ``str`` first: BT.CPP lets any port read text (``convertFromString``), and the entry stays
        text."""
        entry = self.create_entry(key)
        if kind is None or kind is object:
            return
        if entry.declared is None:
            entry.declared = kind
        elif entry.declared is not kind and entry.declared is not str:
            assert kind is not None
            raise BlackboardTypeError(
                f"blackboard entry '{key}' is used by ports of type {entry.declared.__name__} and "
                f"{kind.__name__}; once declared, the type of an entry shall not change"
            )

    def unset(self, key: str) -> None:
        """Remove ``key`` from this blackboard (BT.CPP ``unset``; a missing key is not an error)."""
        if key.startswith("@"):
            self.root.unset(key[1:])
            return
        self._storage.pop(key, None)

    # ---- values --------------------------------------------------------------------------------
    def has(self, key: str) -> bool:
        """True when ``key`` resolves to an entry holding a value."""
        entry = self.entry(key)
        return entry is not None and entry.value is not EMPTY

    def exists(self, key: str) -> bool:
        """True when ``key`` resolves to an entry, empty or not."""
        return self.entry(key) is not None

    def get(self, key: str, default: object = EMPTY) -> object:
        """The value of ``key``; ``default`` when missing or empty, or ``KeyError`` without a default."""
        entry = self.entry(key)
        if entry is None or entry.value is EMPTY:
            if default is EMPTY:
                raise KeyError(key)
            return default
        return entry.value

    def set(self, key: str, value: object) -> None:
        """Write ``key``, creating the entry (in the scope remapping says) when needed, as BT.CPP's
        ``Blackboard::set``: the first number or bool written declares the entry's type; a later scalar of
        another type is converted (text parsed, numbers cast without loss) or refused (BlackboardTypeError)."""
        entry = self.entry(key) or self.create_entry(key)
        kind = scalar_type(value)
        if entry.declared is None:  # BT.CPP: an entry with no type yet takes the value (and its type) as it is
            if kind is not None and kind is not str:
                entry.declared = kind
        elif kind is not None:  # typed: converted to the declared type, then to the type held (copyInto)
            if kind is not entry.declared:
                value = _fit(key, value, entry)
            elif scalar_type(entry.value) is not None:
                value = copy_into(value, entry.value)
        entry.value = value
        entry.sequence_id += 1

    def set_local(self, key: str, value: object) -> None:
        """Write ``key`` in this blackboard itself, ignoring autoremapping (SubTree literal ports); a number
        or bool declares the entry's type, as BT.CPP's typed ``set`` of a literal port does."""
        entry = self._storage.get(key)
        if entry is None:
            entry = self._storage[key] = Entry()
        kind = scalar_type(value)
        if kind is not None and kind is not str:
            entry.declared = kind
        entry.value = value
        entry.sequence_id += 1

    def keys(self) -> Iterator[str]:
        """Keys known to this blackboard itself (including remapped aliases), in creation order."""
        return iter(list(self._storage))

    def items(self) -> dict[str, object]:
        """This blackboard's keys with values (empty entries left out)."""
        return {k: e.value for k, e in self._storage.items() if e.value is not EMPTY}

    def __repr__(self) -> str:
        return f"Blackboard({self.items()!r})"


def _fit(key: str, value: object, entry: Entry) -> object:
    """``value`` converted to the type ``entry`` was declared with (text is parsed, as BT.CPP's ``set``
    parses a string with the entry's converter; numbers are cast without loss)."""
    declared = entry.declared
    assert declared is not None
    try:
        if isinstance(value, str):
            fitted = convert_text(value, declared)
        elif declared in _SCALARS:
            fitted = copy_into(value, declared())
        else:
            raise TreeRuntimeError(f"a {type(value).__name__} is not a {declared.__name__}")
    except TreeRuntimeError as exc:
        raise BlackboardTypeError(
            f"blackboard entry '{key}' holds {declared.__name__}; cannot store {value!r} ({exc})"
        ) from None
    current = entry.value
    return fitted if current is EMPTY or scalar_type(current) is None else copy_into(fitted, current)
