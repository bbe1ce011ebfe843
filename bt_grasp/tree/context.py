"""What a node factory receives: :class:`NodeContext`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from bt_grasp.tree.node import NO_CONDITIONS, BtNode, Conditions, WakeUp

if TYPE_CHECKING:
    from bt_grasp.clock import Clock
    from bt_grasp.tree.blackboard import Blackboard
    from bt_grasp.tree.ports import PortAccessor
    from bt_grasp.tree.registry import NodeKind, NodeSpec


@dataclass(frozen=True)
class NodeContext:
    """Everything a node needs to be constructed; ``__init__`` stores it and does nothing else.

    Attributes:
        name: the instance name (the ``name`` attribute, else the registration ID)
        type_id: the registration ID the node was built as (``Approach``, ``SubTree``)
        uid: BT.CPP-style uid, depth-first from 1 over the expanded tree
        path: BT.CPP ``fullPath``: SubTree instance paths joined by ``/`` then the name (``ID::uid``
            when the node has no name of its own)
        kind: ACTION, CONDITION, CONTROL, DECORATOR or SUBTREE
        spec: the registered spec the node is built from
        ports: read inputs (``ports.get("target")``), write outputs (``ports.set("grasp", g)``)
        clock: simulated time; never read the wall clock
        blackboard: the blackboard of the tree (or SubTree) instance the node is in
        attributes: the attributes exactly as written in the file
        children: the already-built children (controls, decorators, SubTree)
        conditions: parsed pre/post-condition scripts
        enums: scripting enums of the registry
        source: the file the node was written in; ``line`` its line there
        wake_up: the tree's wake-up signal and control-period counter (shared by all its nodes)
    """

    name: str
    type_id: str
    uid: int
    path: str
    kind: NodeKind
    spec: NodeSpec
    ports: PortAccessor
    clock: Clock
    blackboard: Blackboard
    attributes: Mapping[str, str] = field(default_factory=dict)
    children: tuple[BtNode, ...] = ()
    conditions: Conditions = NO_CONDITIONS
    enums: Mapping[str, int] = field(default_factory=dict)
    source: str = ""
    line: int = 0
    wake_up: WakeUp = field(default_factory=WakeUp)

    @property
    def root_blackboard(self) -> Blackboard:
        return self.blackboard.root
