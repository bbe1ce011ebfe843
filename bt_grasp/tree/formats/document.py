"""The format-neutral form of a tree file: what the XML and YAML readers produce and the builder consumes.

Every declaration remembers its file and line so any later problem is reported as ``file:line: problem``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from bt_grasp.errors import TreeFileError

#: the explicit XML tags: ``<Action ID="Approach"/>``
EXPLICIT_TAGS: frozenset[str] = frozenset({"Action", "Condition", "Control", "Decorator"})


@dataclass(frozen=True)
class NodeDecl:
    """One node as written.

    Attributes:
        type_id: the registration ID (``Approach``); ``SubTree`` for a subtree reference
        attributes: every attribute except ``ID``, in file order (``name``, ports, ``_skipIf`` ...)
        children: child nodes in order
        subtree_id: for ``type_id == "SubTree"``, the referenced ``<BehaviorTree ID>``
        explicit_tag: ``Action``/``Condition``/``Control``/``Decorator`` when written in explicit form
    """

    type_id: str
    attributes: tuple[tuple[str, str], ...] = ()
    children: tuple[NodeDecl, ...] = ()
    source: str = ""
    line: int = 0
    subtree_id: str | None = None
    explicit_tag: str | None = None

    def attribute(self, key: str) -> str | None:
        for name, value in self.attributes:
            if name == key:
                return value
        return None

    @property
    def name(self) -> str | None:
        return self.attribute("name")

    def error(self, problem: str) -> TreeFileError:
        return TreeFileError(self.source, problem, where=self.line or None)

    def structure(self) -> tuple[object, ...]:
        """A comparable summary (type, subtree, attributes, children) independent of file and line."""
        return (
            self.type_id,
            self.subtree_id,
            tuple(sorted(self.attributes)),
            tuple(c.structure() for c in self.children),
        )


@dataclass(frozen=True)
class TreeDecl:
    """A ``<BehaviorTree ID="...">`` with its single root node."""

    tree_id: str
    root: NodeDecl
    source: str = ""
    line: int = 0


@dataclass(frozen=True)
class ModelPort:
    name: str
    direction: str  # "input", "output" or "inout"
    type_name: str | None = None
    default: str | None = None
    description: str = ""
    line: int = 0


@dataclass(frozen=True)
class ModelDecl:
    """One node type of ``<TreeNodesModel>``: Groot2's description of a node's ports."""

    kind: str  # Action, Condition, Control, Decorator or SubTree
    node_id: str
    ports: tuple[ModelPort, ...] = ()
    source: str = ""
    line: int = 0


@dataclass(frozen=True)
class IncludeDecl:
    path: str
    source: str = ""
    line: int = 0


@dataclass(frozen=True)
class IncludeLink:
    """One ``<include path>`` as it was resolved: the including file (as displayed), the path as written, and
    the file read for it (as displayed). A log records these so that ``replay --resim`` reads its own copies."""

    source: str
    path: str
    resolved: str


@dataclass
class Document:
    """One file's declarations, or (after includes are merged) all of them.

    Attributes:
        source: the file
        main_tree: ``main_tree_to_execute`` of the first file, None when absent
        trees: by ID, in file order
        models: TreeNodesModel entries
        includes: ``<include path>`` entries as written
        texts: every file read, by path (for recordings)
        include_links: every include as it was resolved (which file was read for it), in reading order
        format_version: the ``BTCPP_format`` attribute (None when absent)
    """

    source: str
    main_tree: str | None = None
    trees: dict[str, TreeDecl] = field(default_factory=dict)
    models: list[ModelDecl] = field(default_factory=list)
    includes: list[IncludeDecl] = field(default_factory=list)
    texts: dict[str, str] = field(default_factory=dict)
    include_links: list[IncludeLink] = field(default_factory=list)
    format_version: str | None = "4"
    root_line: int = 1

    def add_tree(self, tree: TreeDecl) -> None:
        if tree.tree_id in self.trees:
            first = self.trees[tree.tree_id]
            raise TreeFileError(
                tree.source,
                f"a BehaviorTree with ID '{tree.tree_id}' is already defined ({first.source}:{first.line})",
                where=tree.line,
            )
        self.trees[tree.tree_id] = tree

    def structure(self) -> tuple[object, ...]:
        return (
            self.main_tree,
            tuple((k, t.root.structure()) for k, t in self.trees.items()),
            tuple(
                (
                    m.kind,
                    m.node_id,
                    tuple((p.name, p.direction, p.type_name, p.default, p.description) for p in m.ports),
                )
                for m in self.models
            ),
        )
