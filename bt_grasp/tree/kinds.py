"""The two small enums every part of the tree package names: a node's category and a port's direction."""

from __future__ import annotations

import enum


class PortDirection(enum.Enum):
    """Which way a port moves data between a node and its blackboard (BT.CPP ``PortDirection``)."""

    INPUT = "input"
    OUTPUT = "output"
    INOUT = "inout"


class NodeKind(enum.Enum):
    """The BT.CPP node category; the value is the explicit XML tag (``<Action ID=...>``)."""

    ACTION = "Action"
    CONDITION = "Condition"
    CONTROL = "Control"
    DECORATOR = "Decorator"
    SUBTREE = "SubTree"
