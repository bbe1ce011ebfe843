"""Names of the node API's earlier forms, each with the call that replaced it (docs/own-leaves.md's migration
table lists them all): importing one raises :class:`RemovedName` saying what to write instead."""

from __future__ import annotations

from typing import NoReturn

_DECLARE = "declare the class with @action(...), @condition(...), @control(...) or @decorator(...)"

#: module -> removed name -> what replaced it
REMOVED: dict[str, dict[str, str]] = {
    "bt_grasp.tree": {
        "leaf": f"{_DECLARE} from bt_grasp.nodes, then registry.register(MyLeaf)",
        "Leaf": "bt_grasp.nodes.Leaf (every name for writing nodes is in bt_grasp.nodes)",
        "NodeContext": "bt_grasp.nodes.NodeContext",
        "PortSpec": "bt_grasp.nodes.input_port(...), output_port(...) or inout_port(...)",
        "PortDirection": "bt_grasp.nodes.input_port(...), output_port(...) or inout_port(...)",
        "NodeKind": f"{_DECLARE} from bt_grasp.nodes: the decorator says the kind",
        "NodeSpec": f"{_DECLARE} from bt_grasp.nodes, then registry.register(MyNode)",
        "NO_DEFAULT": "leave the default out: input_port(name, type) is an optional port",
    },
    "bt_grasp.nodes": {
        "BtStatus": "bt_grasp.nodes.Status (one status type for leaves, controls and decorators)",
        "PortSpec": "bt_grasp.nodes.input_port(...), output_port(...) or inout_port(...)",
        "PortDirection": "bt_grasp.nodes.input_port(...), output_port(...) or inout_port(...)",
        "NodeSpec": f"{_DECLARE}, then registry.register(MyNode)",
        "NodeKind": f"{_DECLARE}: the decorator says the kind",
        "NO_DEFAULT": "leave the default out: input_port(name, type) is an optional port",
        "leaf": f"{_DECLARE}, then registry.register(MyLeaf)",
    },
    "bt_grasp.tree.builtins.loops": {
        "loop_spec": "bt_grasp.nodes.loop_node(name, item_type, parse_item), registered with registry.register",
    },
}


class RemovedName(ImportError):
    """A name of the node API's earlier form: the message names what replaced it."""


def removed(module: str, name: str) -> NoReturn:
    """For a module's ``__getattr__``: a removed name raises RemovedName, any other AttributeError."""
    replacement = REMOVED.get(module, {}).get(name)
    if replacement is None:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    raise RemovedName(f"{module}.{name} is gone: use {replacement}")
