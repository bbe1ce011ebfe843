"""Behaviour trees: BehaviorTree.CPP v4 XML (and a YAML twin) loaded and run on py_trees with BT.CPP's
semantics. See docs/tree-format.md.

The public entry points::

    from bt_grasp.tree import builtin_registry, load_tree, Leaf, leaf, PortSpec, PortDirection, NodeKind
"""

from __future__ import annotations

from bt_grasp.tree.blackboard import Blackboard
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.leaf import Leaf
from bt_grasp.tree.loader import LoadedTree, load_tree, load_tree_from_string
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import (
    NO_DEFAULT,
    NodeKind,
    NodeRegistry,
    NodeSpec,
    PortDirection,
    PortSpec,
    leaf,
)

__all__ = [
    "NO_DEFAULT",
    "Blackboard",
    "BtNode",
    "BtStatus",
    "Leaf",
    "LoadedTree",
    "NodeContext",
    "NodeKind",
    "NodeRegistry",
    "NodeSpec",
    "PortDirection",
    "PortSpec",
    "builtin_registry",
    "leaf",
    "load_tree",
    "load_tree_from_string",
]
