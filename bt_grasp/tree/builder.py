"""Turn a checked :class:`Document` into py_trees nodes, as BT.CPP's ``XMLParser::instantiateTree`` does.

* uids are given depth-first from 1 over the fully expanded tree (a SubTree node before its content);
* paths follow BT.CPP ``fullPath``: SubTree instance paths joined by ``/``, a node named by its ``name``,
  or ``ID::uid`` when it has none (or its name equals its ID);
* each SubTree instance gets its own :class:`Blackboard`, remapped to its parent's as its attributes say.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Protocol

from bt_grasp.clock import Clock
from bt_grasp.errors import TreeFileError
from bt_grasp.tree.blackboard import Blackboard, BlackboardTypeError
from bt_grasp.tree.builtins.subtree import SubTreeNode
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import PortValueError, ScriptSyntaxError
from bt_grasp.tree.formats.document import Document, NodeDecl
from bt_grasp.tree.node import BtNode, Conditions, WakeUp
from bt_grasp.tree.ports import PortAccessor, blackboard_key
from bt_grasp.tree.registry import NodeKind, NodeRegistry, NodeSpec
from bt_grasp.tree.substitution import SubstitutionRule, substitute
from bt_grasp.tree.validate import (
    check_known_nodes,
    check_models,
    check_read_only_ports,
    resolve_node,
    resolve_subtree,
)
from bt_grasp.tree.values import literal_value


class NodeReplacer(Protocol):
    """BT.CPP's substitution rules, asked about every node as BT.CPP's ``instantiateTreeNode`` does
    (:class:`bt_grasp.tree.test_node.RuleSet`): the leaf spec that replaces the node, named like it, or None. A
    replaced control's children are built all the same and left out of the tree (their uids and blackboard
    entries are BT.CPP's), a replaced SubTree's content is not built."""

    def replace(self, kind: NodeKind, type_id: str, name: str, path: str) -> NodeSpec | None: ...


SUBTREE_SPEC = NodeSpec(
    "SubTree", NodeKind.SUBTREE, (), lambda ctx: SubTreeNode(ctx, ""), "Runs a BehaviorTree on its own blackboard."
)


def main_tree_id(document: Document) -> str:
    """``main_tree_to_execute``, or the only tree; otherwise a :class:`TreeFileError`."""
    trees = list(document.trees)
    if document.main_tree is not None:
        if document.main_tree not in document.trees:
            listing = ", ".join(trees) or "none"
            raise TreeFileError(
                document.source,
                f'main_tree_to_execute="{document.main_tree}" names no BehaviorTree (trees: {listing})',
                where=document.root_line,
            )
        return document.main_tree
    if len(trees) == 1:
        return trees[0]
    if not trees:
        raise TreeFileError(document.source, "the file defines no <BehaviorTree>", where=document.root_line)
    raise TreeFileError(
        document.source,
        f"the file defines {len(trees)} BehaviorTrees ({', '.join(trees)}); "
        f'say which one runs with main_tree_to_execute="{trees[0]}" on <root>',
        where=document.root_line,
    )


def validate_document(document: Document, registry: NodeRegistry) -> str:
    """Check every tree of ``document`` (not only the main one) and its models; returns the main tree ID."""
    check_models(document, registry)
    check_known_nodes(document, registry)
    check_read_only_ports(document)

    def walk(decl: NodeDecl) -> None:
        if decl.type_id == "SubTree":
            resolve_subtree(decl, document, SUBTREE_SPEC)
            return
        resolve_node(decl, registry, document)
        for child in decl.children:
            walk(child)

    for tree in document.trees.values():
        walk(tree.root)
    main = main_tree_id(document)
    _check_cycles(document, main)
    return main


#: nodes the main tree may expand to, every SubTree counted as often as it is used (40 trees each using the next
#: twice are 2^40 nodes: checking them one by one never finished), and how deep it may nest once expanded
MAX_EXPANDED_NODES = 100_000
MAX_EXPANDED_DEPTH = 100  # = the depth a log of the run may hold (bt_grasp.recording.validate.MAX_TREE_DEPTH)


def _check_cycles(document: Document, main: str) -> None:
    """No SubTree uses itself, directly or not, and the expanded tree stays within :data:`MAX_EXPANDED_NODES` nodes
    and :data:`MAX_EXPANDED_DEPTH` levels: each tree's expanded size and depth is computed once (memoised), so
    the check is linear in the file, however often its subtrees are reused."""
    expanded: dict[str, tuple[int, int]] = {}  # tree id -> (nodes, depth) once expanded

    def visit(tree_id: str, stack: tuple[str, ...]) -> tuple[int, int]:
        if tree_id in expanded:
            return expanded[tree_id]
        nodes, deepest = 0, 0
        todo: list[tuple[NodeDecl, int]] = [(document.trees[tree_id].root, 1)]
        while todo:
            decl, depth = todo.pop()
            nodes += 1
            if decl.type_id == "SubTree":
                target = decl.subtree_id or ""
                if target in stack or target == tree_id:
                    raise decl.error(f"cyclic SubTree: {' -> '.join((*stack, tree_id, target))}")
                inner_nodes, inner_depth = visit(target, (*stack, tree_id))
                nodes, depth = nodes + inner_nodes, depth + inner_depth
            else:
                todo.extend((child, depth + 1) for child in decl.children)
            deepest = max(deepest, depth)
            if nodes > MAX_EXPANDED_NODES:
                raise decl.error(f"the tree expands to more than {MAX_EXPANDED_NODES:,} nodes (each SubTree counted "
                                 "as often as it is used)")
            if deepest > MAX_EXPANDED_DEPTH:
                raise decl.error(f"the tree nests deeper than {MAX_EXPANDED_DEPTH} levels once its SubTrees are "
                                 "expanded")
        expanded[tree_id] = (nodes, deepest)
        return nodes, deepest

    visit(main, ())


@dataclass
class TreeBuilder:
    document: Document
    registry: NodeRegistry
    clock: Clock
    rules: tuple[SubstitutionRule, ...] = ()
    replacer: NodeReplacer | None = None
    _uids: itertools.count[int] = field(default_factory=lambda: itertools.count(1))
    wake_up: WakeUp = field(default_factory=WakeUp)
    #: the ``rules`` patterns that replaced a node
    substituted: set[str] = field(default_factory=set)

    def build(self, main: str, root_blackboard: Blackboard) -> BtNode:
        return self._node(self.document.trees[main].root, root_blackboard, "", "", (main,))

    def _context(self, decl: NodeDecl, *, name: str, type_id: str, uid: int, path: str, spec: NodeSpec,
                 ports: PortAccessor, blackboard: Blackboard, children: tuple[BtNode, ...],
                 conditions: Conditions) -> NodeContext:
        return NodeContext(
            name=name, type_id=type_id, uid=uid, path=path, kind=spec.kind, spec=spec, ports=ports, clock=self.clock,
            blackboard=blackboard, attributes=dict(decl.attributes), children=children, conditions=conditions,
            enums=self.registry.enums, source=decl.source, line=decl.line, wake_up=self.wake_up,
        )

    def _node(self, decl: NodeDecl, bb: Blackboard, prefix: str, instance: str, stack: tuple[str, ...]) -> BtNode:
        uid = next(self._uids)
        if decl.type_id == "SubTree":
            return self._subtree(decl, uid, bb, prefix, instance, stack)
        resolved = resolve_node(decl, self.registry, self.document)
        spec, name, ports = resolved.spec, resolved.name, resolved.ports
        path = prefix + name + (f"::{uid}" if name == decl.type_id else "")
        foreign = spec.needs_robot or spec.name in self.registry.origins
        match = substitute(self.rules, spec, decl.type_id, name, path, foreign=foreign)
        if match is not None:
            spec, ports = match[1], {}
            self.substituted.add(match[0].pattern)
        for value in ports.values():  # before the children's, as BT.CPP creates a parent before its children
            if value.key is not None:
                try:
                    bb.declare(value.key, value.port.type)
                except BlackboardTypeError as exc:
                    raise decl.error(f"{spec.name}: port '{value.port.name}': {exc}") from None
        children = tuple(self._node(c, bb, prefix, instance, stack) for c in decl.children)
        replacer = self.replacer if match is None else None
        replaced = replacer.replace(spec.kind, decl.type_id, name, path) if replacer is not None else None
        if replaced is not None:  # BT.CPP: the children were made, and belong to no parent
            spec, children = replaced, ()
            ports = {k: v for k, v in ports.items() if replaced.port(k) is not None}
        ctx = self._context(
            decl,
            name=name,
            type_id=spec.name,
            uid=uid,
            path=path,
            spec=spec,
            ports=PortAccessor({p.name: p for p in spec.ports}, ports, bb, path),
            blackboard=bb,
            children=children,
            conditions=resolved.conditions,
        )
        assert spec.factory is not None
        try:
            node = spec.factory(ctx)
        except (ScriptSyntaxError, PortValueError) as exc:
            raise decl.error(f"{spec.name}: {exc}") from None
        except Exception as exc:  # a plugin's node that cannot be built is the plugin's problem, named in one line
            origin = self.registry.origins.get(spec.name)
            if origin is None:
                raise
            raise decl.error(f"{spec.name} (from {origin}) could not be built: {type(exc).__name__}: {exc}") from None
        if not isinstance(node, BtNode):
            problem = f"the factory of {spec.name} returned {type(node).__name__}, not a bt_grasp Leaf/BtNode"
            if spec.name in self.registry.origins:
                raise decl.error(problem)
            raise TypeError(problem)
        return node

    def _subtree(
        self, decl: NodeDecl, uid: int, bb: Blackboard, prefix: str, instance: str, stack: tuple[str, ...]
    ) -> BtNode:
        resolved = resolve_subtree(decl, self.document, SUBTREE_SPEC)
        subtree_id = decl.subtree_id or ""
        if subtree_id in stack:
            raise decl.error(f"cyclic SubTree: {' -> '.join((*stack, subtree_id))}")
        name = resolved.name
        path = prefix + name + (f"::{uid}" if name == subtree_id else "")
        replaced = self.replacer.replace(NodeKind.SUBTREE, "SubTree", name, path) if self.replacer else None
        if replaced is not None:  # BT.CPP: a replaced SubTree's content is never made
            return self._replaced_subtree(decl, replaced, uid, bb, name, path, resolved.conditions)
        inner = Blackboard(bb, autoremap=resolved.autoremap)
        for port, value in resolved.remaps:
            key = blackboard_key(value, port)
            if key is not None:
                inner.add_remapping(port, key)
            else:  # a literal: an integer, a real or text, as BT.CPP 4.10 types it
                inner.set_local(port, literal_value(value))
        sub_instance = (instance + "/" if instance else "") + (decl.name or f"{subtree_id}::{uid}")
        tree = self.document.trees[subtree_id]
        child = self._node(tree.root, inner, sub_instance + "/", sub_instance, (*stack, subtree_id))
        ctx = self._context(
            decl,
            name=name,
            type_id="SubTree",
            uid=uid,
            path=path,
            spec=SUBTREE_SPEC,
            ports=PortAccessor({}, {}, bb, path),
            blackboard=bb,
            children=(child,),
            conditions=resolved.conditions,
        )
        node = SubTreeNode(ctx, subtree_id)
        node.subtree_blackboard = inner
        node.subtree_path = sub_instance
        return node

    def _replaced_subtree(self, decl: NodeDecl, spec: NodeSpec, uid: int, bb: Blackboard, name: str, path: str,
                          conditions: Conditions) -> BtNode:
        ctx = self._context(decl, name=name, type_id=spec.name, uid=uid, path=path, spec=spec,
                            ports=PortAccessor({p.name: p for p in spec.ports}, {}, bb, path), blackboard=bb,
                            children=(), conditions=conditions)
        assert spec.factory is not None
        return spec.factory(ctx)
