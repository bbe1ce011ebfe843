"""Load a tree file (XML or YAML, following includes), check it completely, then build it.

``load_tree`` either returns a :class:`LoadedTree` or raises :class:`bt_grasp.errors.TreeFileError`
(``file:line: problem``); nothing is ticked while loading.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path

import py_trees

from bt_grasp.clock import Clock, ManualClock
from bt_grasp.errors import TreeFileError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.search_path import SHIPPED_TREES, TREE_PATH_VARIABLE, find_named_file, looked_in
from bt_grasp.tree.blackboard import Blackboard
from bt_grasp.tree.builder import NodeReplacer, TreeBuilder, validate_document
from bt_grasp.tree.formats.document import Document, IncludeDecl, IncludeLink
from bt_grasp.tree.formats.xml_format import read_xml
from bt_grasp.tree.formats.yaml_format import read_yaml
from bt_grasp.tree.introspect import to_btcpp_xml
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import NodeRegistry
from bt_grasp.tree.substitution import parse_rules

logger = logging.getLogger(__name__)


def sniff_format(display: str, data: bytes) -> str:
    suffix = os.path.splitext(display)[1].lower()
    if suffix == ".xml":
        return "xml"
    if suffix in (".yaml", ".yml"):
        return "yaml"
    return "xml" if data.lstrip()[:1] == b"<" else "yaml"


def parse_bytes(data: bytes, display: str, fmt: str | None = None) -> Document:
    fmt = fmt or sniff_format(display, data)
    document = read_xml(data, display) if fmt == "xml" else read_yaml(data, display)
    document.texts[display] = data.decode("utf-8", errors="replace")
    return document


def _read_bytes(path: Path, display: str) -> bytes:
    try:
        if not path.exists():
            raise FileNotFoundError(path)
        if path.is_dir():
            raise IsADirectoryError(path)
        return read_user_file(path, error=TreeFileError)  # bounded: no device, pipe or giant file
    except FileNotFoundError:
        raise TreeFileError(display, "no such file") from None
    except IsADirectoryError:
        raise TreeFileError(display, "is a directory, not a tree file") from None
    except OSError as exc:
        raise TreeFileError(display, f"cannot read the file: {exc.strerror}") from None


#: ``replay --resim``: the log's own files for each include, by (including file's real path, path as written);
#: while set, an include is resolved here only (no folder, search path or shipped library is looked at)
_recorded_includes: ContextVar[Mapping[tuple[str, str], Path] | None] = ContextVar("bt_grasp_recorded_includes",
                                                                                  default=None)


@contextmanager
def recorded_includes(links: Mapping[tuple[str, str], Path]) -> Iterator[None]:
    """Within the block, every include is resolved through ``links`` only: ``(os.path.realpath(including file),
    path as written) -> the file to read``; an include not in it is refused (exit 2)."""
    token = _recorded_includes.set(dict(links))
    try:
        yield
    finally:
        _recorded_includes.reset(token)


def resolve_include(inc: IncludeDecl, including: str) -> str:
    """The file an include names, as displayed: beside the including file, then each folder of
    ``BT_GRASP_TREE_PATH``, then bt_grasp's shipped library (``bt_grasp/files/search_path.py``); an absolute
    path as it is. Not found: one sentence naming every place looked."""
    recorded = _recorded_includes.get()
    if recorded is not None:
        target = recorded.get((os.path.realpath(including), inc.path))
        if target is None:
            raise TreeFileError(inc.source, f"included file '{inc.path}' is not among the files the log carries, so "
                                "this run cannot be re-simulated", where=inc.line)
        return str(target)
    found = find_named_file(inc.path, Path(os.path.dirname(including)), TREE_PATH_VARIABLE, SHIPPED_TREES)
    if found.path is None:
        raise TreeFileError(inc.source, f"included file '{inc.path}' does not exist: "
                            f"{looked_in(found, TREE_PATH_VARIABLE)}", where=inc.line)
    return str(found.path)


def read_single(path: Path) -> Document:
    """One file, its includes listed but not followed."""
    display = str(path)
    return parse_bytes(_read_bytes(path, display), display)


def _merge_includes(document: Document, display: str, stack: tuple[str, ...], seen: set[str]) -> None:
    for inc in list(document.includes):
        inc_display = resolve_include(inc, display)
        document.include_links.append(IncludeLink(display, inc.path, inc_display))
        key = os.path.realpath(inc_display)
        if key in stack:
            chain = " -> ".join([*(os.path.basename(s) for s in stack), os.path.basename(key)])
            raise TreeFileError(inc.source, f"include cycle: {chain}", where=inc.line)
        if key in seen:
            continue
        seen.add(key)
        included = parse_bytes(_read_bytes(Path(inc_display), inc_display), inc_display)
        _merge_includes(included, inc_display, (*stack, key), seen)
        for tree in included.trees.values():
            document.add_tree(tree)
        document.models.extend(included.models)
        document.texts.update(included.texts)
        document.include_links.extend(included.include_links)


def read_document(data: bytes, display: str, fmt: str | None = None) -> Document:
    """Parse ``data`` and merge every file it includes (found by :func:`resolve_include`)."""
    document = parse_bytes(data, display, fmt)
    key = os.path.realpath(display)
    _merge_includes(document, display, (key,), {key})
    return document


@dataclass
class LoadedTree:
    """A built tree, ready to tick.

    Attributes:
        root: the py_trees root (a :class:`BtNode`)
        root_blackboard: the main tree's blackboard
        main_tree: the ID of the tree that runs
        document: every declaration read (all files, includes merged)
        clock: the clock Timeout, Delay and Sleep read
        sources: every file's text, by path as displayed
    """

    root: BtNode
    root_blackboard: Blackboard
    main_tree: str
    document: Document
    clock: Clock
    sources: dict[str, str] = field(default_factory=dict)
    status: BtStatus = BtStatus.IDLE
    ticks: int = 0
    #: the ``substitutions`` patterns that replaced at least one node
    substituted: frozenset[str] = frozenset()

    def tick(self) -> BtStatus:
        """One control period, as BT.CPP's ``tickOnce``: a completed root is reset to IDLE first, then the root
        is executed, and again while it is RUNNING and a node requested a wake-up (see :attr:`runs`)."""
        for _ in self.root.tick():
            pass
        self.ticks += 1
        self.status = self.root.bt_last_root_status
        return self.status

    @property
    def runs(self) -> int:
        """How many times the last :meth:`tick` executed the root (1 + wake-up re-runs)."""
        return self.root.bt_wake_up.runs

    def halt(self) -> None:
        """Halt the whole tree (every RUNNING node gets ``terminate(INVALID)``)."""
        self.root.stop(py_trees.common.Status.INVALID)

    def nodes(self) -> Iterator[BtNode]:
        for node in self.root.iterate():
            if isinstance(node, BtNode):
                yield node

    def find(self, name_or_path: str) -> BtNode:
        """The node with this path, or the only node with this name."""
        by_name = [n for n in self.nodes() if n.bt_path == name_or_path or n.name == name_or_path]
        exact = [n for n in by_name if n.bt_path == name_or_path]
        if exact:
            return exact[0]
        if len(by_name) != 1:
            raise KeyError(f"{len(by_name)} nodes are called {name_or_path!r}")
        return by_name[0]

    def robot_nodes(self) -> list[BtNode]:
        """Leaves whose spec needs the robot (``needs_robot``), after substitution."""
        return [n for n in self.nodes() if n.bt_spec.needs_robot]

    @property
    def btcpp_xml(self) -> str:
        """The expanded tree as BT.CPP writes it for Groot2 (``_uid`` and ``_fullpath`` attributes)."""

        return to_btcpp_xml(self.root, self.main_tree)

    def blackboard_values(self) -> dict[str, object]:
        return self.root_blackboard.items()


def build_tree(
    document: Document,
    registry: NodeRegistry,
    *,
    substitutions: Mapping[str, str] | None = None,
    clock: Clock | None = None,
    replacer: NodeReplacer | None = None,
) -> LoadedTree:
    """Check ``document`` completely, then build its main tree (``replacer``: BT.CPP's substitution rules, see
    :class:`bt_grasp.tree.builder.NodeReplacer`)."""
    rules = parse_rules(substitutions, registry)
    main = validate_document(document, registry)
    clock = clock or ManualClock()
    root_blackboard = Blackboard()
    builder = TreeBuilder(document, registry, clock, rules, replacer)
    root = builder.build(main, root_blackboard)
    logger.debug("built %s from %s", main, document.source)
    return LoadedTree(root, root_blackboard, main, document, clock, dict(document.texts),
                      substituted=frozenset(builder.substituted))


def read_tree_file(path: str | Path) -> Document:
    """A tree file's declarations, every include merged (bounded reads), nothing checked against a registry."""
    display = str(path)
    return read_document(_read_bytes(Path(path), display), display)


def load_tree(
    path: str | Path,
    registry: NodeRegistry,
    *,
    substitutions: Mapping[str, str] | None = None,
    clock: Clock | None = None,
) -> LoadedTree:
    """Load a BT.CPP v4 XML or YAML tree file (by extension; content sniffed otherwise).

    Args:
        path: the file; an include is looked for beside the file that names it, then in each folder of
            ``BT_GRASP_TREE_PATH``, then in bt_grasp's shipped library (``lib/pick.xml``, ``lib/place.xml``)
        registry: the node types the file may use
        substitutions: ``{"Perceive": "AlwaysSuccess", "Approach*": "Running:3"}`` (see ``substitution``)
        clock: simulated time for Timeout, Delay and Sleep (a new ``ManualClock`` when None)
    """
    return build_tree(read_tree_file(path), registry, substitutions=substitutions, clock=clock)


def load_tree_from_string(
    text: str,
    registry: NodeRegistry,
    *,
    fmt: str = "xml",
    source: str = "<string>",
    substitutions: Mapping[str, str] | None = None,
    clock: Clock | None = None,
) -> LoadedTree:
    """Like :func:`load_tree` for text in memory (includes are looked for from the working directory first)."""
    document = read_document(text.encode("utf-8"), source, fmt)
    return build_tree(document, registry, substitutions=substitutions, clock=clock)
