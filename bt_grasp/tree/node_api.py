"""The node API as the tree package itself uses it: every name of :mod:`bt_grasp.nodes` but ``RobotLeaf``.

bt_grasp's built-in nodes (``bt_grasp.tree.builtins``) import from here exactly what a plugin imports from
``bt_grasp.nodes`` (the same objects: ``bt_grasp.nodes`` re-exports this module and adds the robot leaves' base);
they import it here only because the tree package sits on a lower floor than ``bt_grasp.nodes``.
"""

from __future__ import annotations

from bt_grasp.clock import Clock
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.control_node import Control
from bt_grasp.tree.deadline import Deadline
from bt_grasp.tree.declare import action, condition, control, decorator, inout_port, input_port, output_port
from bt_grasp.tree.decorator_node import Decorator
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.loop_node import Loop, loop_node
from bt_grasp.tree.node import BtNode
from bt_grasp.tree.node import BtStatus as Status
from bt_grasp.tree.plugins import ENTRY_POINT_GROUP, PluginError
from bt_grasp.tree.ports import PortAccessor
from bt_grasp.tree.reasons import FailureReason, Reason, ReasonLike
from bt_grasp.tree.registry import NodeRegistry

__all__ = [
    "ENTRY_POINT_GROUP",
    "BtNode",
    "Clock",
    "Control",
    "Deadline",
    "DeclarationError",
    "Decorator",
    "FailureReason",
    "Leaf",
    "Loop",
    "NodeContext",
    "NodeRegistry",
    "PluginError",
    "PortAccessor",
    "Reason",
    "ReasonLike",
    "Status",
    "action",
    "condition",
    "control",
    "decorator",
    "inout_port",
    "input_port",
    "loop_node",
    "output_port",
]
