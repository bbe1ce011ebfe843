"""The node standing for a ``<SubTree>`` (BT.CPP ``SubTreeNode``)."""

from __future__ import annotations

from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.decorator_node import Decorator
from bt_grasp.tree.node import BtStatus


class SubTreeNode(Decorator):
    """The node standing for a ``<SubTree>``: its child is the subtree's root, on its own blackboard."""

    def __init__(self, ctx: NodeContext, subtree_id: str) -> None:
        super().__init__(ctx)
        self.subtree_id = subtree_id
        #: the SubTree instance's own blackboard and instance path (set by the builder)
        self.subtree_blackboard = ctx.blackboard
        self.subtree_path = ctx.path

    def bt_tick(self) -> BtStatus:
        if self.bt_state is BtStatus.IDLE:
            self.set_bt_status(BtStatus.RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
        return status
