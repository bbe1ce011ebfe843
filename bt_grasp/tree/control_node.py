"""Base class of control nodes (BT.CPP's ``ControlNode``): children, and the calls that tick and halt them."""

from __future__ import annotations

from typing import TYPE_CHECKING, NoReturn

import py_trees

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus, as_behaviour

if TYPE_CHECKING:
    from bt_grasp.clock import Clock
    from bt_grasp.tree.blackboard import Blackboard
    from bt_grasp.tree.context import NodeContext
    from bt_grasp.tree.ports import PortAccessor


class Control(BtNode, py_trees.composites.Composite):
    """A control node: implement ``bt_tick() -> Status`` with BT.CPP's rules (its ``tick()``), and ``halt()`` to
    clear your own state before ``super().halt()``.

    Attributes:
        child_nodes: the children, in order (BT.CPP's ``children()``)
        ports, clock, blackboard: as a leaf's (the tree instance's blackboard: BT.CPP's ``config().blackboard``)
    """

    ports: PortAccessor
    clock: Clock
    blackboard: Blackboard

    def __init__(self, ctx: NodeContext) -> None:
        py_trees.composites.Composite.__init__(self, ctx.name, [as_behaviour(child) for child in ctx.children])
        self._bt_bind(ctx)
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard
        self.child_nodes: list[BtNode] = list(ctx.children)

    def tick_child(self, index: int) -> BtStatus:
        """Tick child ``index`` (BT.CPP's ``children_nodes_[index]->executeTick()``) and return its status."""
        status = self.child_nodes[index].execute_tick()
        if status is BtStatus.IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: a child returned IDLE")
        return status

    def halt_child(self, index: int) -> None:
        """BT.CPP's ``haltChild(i)``: halt child ``index`` when it is RUNNING, then set it back to IDLE."""
        child = self.child_nodes[index]
        if child.bt_state is BtStatus.RUNNING:
            child.halt_node()
        child.reset_status()

    def halt_children(self, first: int = 0) -> None:
        """BT.CPP's ``haltChildren(first)``: :meth:`halt_child` for every child from ``first`` on."""
        for index in range(first, len(self.child_nodes)):
            self.halt_child(index)

    def reset_children(self) -> None:
        """BT.CPP 4.10's ``resetChildren()``: every child back to IDLE, a RUNNING one halted first (so the same as
        :meth:`halt_children`; BT.CPP's controls call it once they complete)."""
        self.halt_children()

    def halt(self) -> None:
        """Halted by the parent: every child halted and reset, then this node IDLE (BT.CPP's ``ControlNode::halt``)."""
        self.reset_children()
        self.reset_status()

    # ---- names of an earlier API, kept only to say what replaced them ----------------------------------------
    def _tick_child(self, index: int) -> NoReturn:
        raise TreeRuntimeError(f"{self.bt_path}: _tick_child(i) is now tick_child(i)")

    @property
    def kids(self) -> NoReturn:
        raise AttributeError(f"{type(self).__name__}.kids is now child_nodes")
