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
from typing import Any


class _Empty:
    def __repr__(self) -> str:
        return "<empty>"


#: the value of an entry that was declared (a port points to it) but never written
EMPTY: Any = _Empty()


class Entry:
    """One blackboard value; shared between blackboards that remap to it."""

    __slots__ = ("sequence_id", "value")

    def __init__(self, value: Any = EMPTY) -> None:
        self.value = value
        self.sequence_id = 0


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

    def declare(self, key: str) -> None:
        """Create an empty entry (BT.CPP creates one for every ``{key}`` port when it builds a tree)."""
        self.create_entry(key)

    # ---- values --------------------------------------------------------------------------------
    def has(self, key: str) -> bool:
        """True when ``key`` resolves to an entry holding a value."""
        entry = self.entry(key)
        return entry is not None and entry.value is not EMPTY

    def exists(self, key: str) -> bool:
        """True when ``key`` resolves to an entry, empty or not."""
        return self.entry(key) is not None

    def get(self, key: str, default: Any = EMPTY) -> Any:
        """The value of ``key``; ``default`` when missing or empty, or ``KeyError`` without a default."""
        entry = self.entry(key)
        if entry is None or entry.value is EMPTY:
            if default is EMPTY:
                raise KeyError(key)
            return default
        return entry.value

    def set(self, key: str, value: Any) -> None:
        """Write ``key``, creating the entry (in the scope remapping says) when needed."""
        entry = self.entry(key) or self.create_entry(key)
        entry.value = value
        entry.sequence_id += 1

    def set_local(self, key: str, value: Any) -> None:
        """Write ``key`` in this blackboard itself, ignoring autoremapping (SubTree literal ports)."""
        entry = self._storage.get(key)
        if entry is None:
            entry = self._storage[key] = Entry()
        entry.value = value
        entry.sequence_id += 1

    def keys(self) -> Iterator[str]:
        """Keys known to this blackboard itself (including remapped aliases), in creation order."""
        return iter(list(self._storage))

    def items(self) -> dict[str, Any]:
        """This blackboard's keys with values (empty entries left out)."""
        return {k: e.value for k, e in self._storage.items() if e.value is not EMPTY}

    def __repr__(self) -> str:
        return f"Blackboard({self.items()!r})"
