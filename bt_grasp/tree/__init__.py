"""Behaviour trees: BehaviorTree.CPP v4 XML (and a YAML twin) loaded and run on py_trees with BT.CPP's
semantics. See docs/tree-format.md; nodes of one's own are written against :mod:`bt_grasp.nodes`.

The public entry points::

    from bt_grasp.tree import builtin_registry, load_tree, load_tree_from_string
"""

from __future__ import annotations

from typing import NoReturn

from bt_grasp.tree.blackboard import Blackboard
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.loader import LoadedTree, load_tree, load_tree_from_string
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import NodeRegistry
from bt_grasp.tree.removed import removed

__all__ = [
    "Blackboard",
    "BtNode",
    "BtStatus",
    "LoadedTree",
    "NodeRegistry",
    "builtin_registry",
    "load_tree",
    "load_tree_from_string",
]


def __getattr__(name: str) -> NoReturn:
    removed(__name__, name)
