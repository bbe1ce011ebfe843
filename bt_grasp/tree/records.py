"""The typed records a running tree hands to everything that watches it (recorders, the live server, the
control API, replay and reports): one node's state in one tick, and a node of the tree's static structure.

They are ``TypedDict``s, not classes, on purpose: they travel as JSON (the log's ``/bt/tick`` and ``/bt/tree``
messages, the live view) and through the writer process, and a dict is what those encode without a copy.
The keys are the log's format (``bt_grasp.recording.topics`` keeps its history); a key read from a log is
checked by ``bt_grasp.recording.validate`` before it is trusted to have these types.
"""

from __future__ import annotations

from typing import NotRequired, TypedDict


class NodeRecord(TypedDict):
    """One node in one tick (``tree.runner.tick_records``)."""

    uid: int  # the node's number in the tree (depth-first, from 1): its identity within one run
    type: str  # its registration ID (``Sequence``, ``Perceive``, ...)
    name: str  # its ``name`` attribute (else its type)
    path: str  # its one name in every output (``docs/recording.md``, "One name per node")
    kind: str  # ``NodeKind`` value: Action, Condition, Control, Decorator, SubTree
    status: str  # what it returned this tick if ticked, else its BT.CPP status (IDLE, RUNNING, ...)
    failure_reason: str | None  # a leaf's typed reason for its last FAILURE
    ticked: bool  # ticked in this tick
    feedback: str  # the node's feedback message


class NodeSnapshot(TypedDict):
    """One node as it stands between ticks (``tree.introspect.node_records``): its py_trees and BT.CPP status."""

    uid: int
    type: str
    name: str
    path: str
    kind: str
    status: str  # py_trees' name (SUCCESS, FAILURE, RUNNING, INVALID)
    bt_status: str  # BT.CPP's name (IDLE, RUNNING, SUCCESS, FAILURE, SKIPPED)
    feedback_message: str
    failure_reason: str | None


class TreeNode(TypedDict):
    """One node of the tree's static structure (``tree.introspect.tree_structure``; the log's ``/bt/tree``)."""

    uid: int
    type: str
    name: str
    path: str
    kind: str
    attributes: dict[str, str]  # as written in the tree file
    children: list[TreeNode]
    subtree_id: NotRequired[str]  # a SubTree instance's tree ID
