"""Base class of decorators (BT.CPP's ``DecoratorNode``): one child, and the calls that tick and halt it."""

from __future__ import annotations

from typing import TYPE_CHECKING

import py_trees

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus, as_behaviour

if TYPE_CHECKING:
    from bt_grasp.clock import Clock
    from bt_grasp.tree.blackboard import Blackboard
    from bt_grasp.tree.context import NodeContext
    from bt_grasp.tree.ports import PortAccessor


class Decorator(BtNode, py_trees.decorators.Decorator):
    """A decorator: implement ``bt_tick() -> Status`` with BT.CPP's rules (its ``tick()``), and ``halt()`` to
    clear your own state before ``super().halt()``.

    Attributes:
        child: the one child (BT.CPP's ``child()``)
        ports, clock, blackboard: as a leaf's (the tree instance's blackboard: BT.CPP's ``config().blackboard``)
    """

    ports: PortAccessor
    clock: Clock
    blackboard: Blackboard

    def __init__(self, ctx: NodeContext) -> None:
        (child,) = ctx.children
        py_trees.decorators.Decorator.__init__(self, ctx.name, as_behaviour(child))
        self._bt_bind(ctx)
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard
        self.child: BtNode = child

    def update(self) -> py_trees.common.Status:  # pragma: no cover - py_trees never calls it here
        return self.status

    def execute_tick(self) -> BtStatus:
        """BT.CPP ``DecoratorNode::executeTick``: a child left SUCCESS or FAILURE goes back to IDLE."""
        status = super().execute_tick()
        if self.child.bt_state.completed:
            self.child.reset_status()
        return status

    def tick_child(self) -> BtStatus:
        """Tick the child (BT.CPP's ``child_node_->executeTick()``) and return its status."""
        status = self.child.execute_tick()
        if status is BtStatus.IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: the child returned IDLE")
        return status

    def halt_child(self) -> None:
        """BT.CPP's ``haltChild()``/``resetChild()``: halt the child when it is RUNNING, then set it back to IDLE."""
        if self.child.bt_state is BtStatus.RUNNING:
            self.child.halt_node()
        self.child.reset_status()

    def reset_child(self) -> None:
        """The same as :meth:`halt_child` (BT.CPP 4.10's ``resetChild()``)."""
        self.halt_child()

    def halt(self) -> None:
        """Halted by the parent: the child halted and reset, then this node IDLE."""
        self.halt_child()
        self.reset_status()
