"""The one API for writing nodes: leaves, controls, decorators and failure reasons, as bt_grasp writes its own.

Every name a plugin needs is here (docs/own-leaves.md has the table and a complete example); bt_grasp's built-in
nodes and robot leaves are declared and registered with these same calls, so any of them is a template::

    from bt_grasp.nodes import Deadline, NodeRegistry, Reason, RobotLeaf, Status, action, input_port

    BARCODE_UNREADABLE = Reason("BARCODE_UNREADABLE", "The label could not be read.")

    @action(ports=[input_port("timeout_s", float, 2.0, "give up after this much simulated time")],
            needs_robot=True, reasons=[BARCODE_UNREADABLE])
    class ReadBarcode(RobotLeaf):
        '''Reads the barcode of the object in front of the camera.'''

        def initialise(self) -> None:               # one attempt starts
            self.deadline = Deadline.after(self.clock, self.ports.require("timeout_s", float))

        def update(self) -> Status:                 # once per tick (one control period), never blocks
            frame = self.cell.camera.capture()
            ...
            if self.deadline.passed():
                return self.fail(BARCODE_UNREADABLE, "no label found before the timeout")
            return Status.RUNNING

    def register(registry: NodeRegistry) -> None:  # BT.CPP's BT_REGISTER_NODES
        registry.register(ReadBarcode)              # BT.CPP's registerNodeType<ReadBarcode>

The declaration (``@action``, ``@condition``, ``@control``, ``@decorator``) is the node's manifest, as BT.CPP's
``providedPorts()``. The lifecycle is py_trees' with BT.CPP's halting: ``__init__`` stores configuration only;
``setup(cell=...)`` receives the run's services once; ``initialise()`` starts an attempt; ``update()`` runs once
per tick and returns a :data:`Status` (RUNNING, SUCCESS, FAILURE or SKIPPED); ``terminate(new_status)`` follows a
completed update, or comes with ``Status.IDLE`` when a parent halts the RUNNING leaf. Controls and decorators
implement ``bt_tick() -> Status`` (BT.CPP's ``tick()``) with ``tick_child``, ``halt_child``, ``halt_children``
and ``reset_children``. Time is simulated: read ``self.clock`` (or use :class:`Deadline`), never the wall clock.
"""

from __future__ import annotations

from typing import NoReturn

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.tree.node_api import (
    ENTRY_POINT_GROUP,
    BtNode,
    Clock,
    Control,
    Deadline,
    DeclarationError,
    Decorator,
    FailureReason,
    Leaf,
    Loop,
    NodeContext,
    NodeRegistry,
    PluginError,
    PortAccessor,
    Reason,
    ReasonLike,
    Status,
    action,
    condition,
    control,
    decorator,
    inout_port,
    input_port,
    loop_node,
    output_port,
)
from bt_grasp.tree.removed import removed

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
    "RobotLeaf",
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


def __getattr__(name: str) -> NoReturn:
    removed(__name__, name)
