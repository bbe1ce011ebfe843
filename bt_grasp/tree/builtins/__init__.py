"""Every built-in node type, with BT.CPP v4's registration IDs and port names, one module per family (as BT.CPP's
``src/controls``, ``src/decorators``, ``src/actions``). Each module declares its nodes with the node API and
registers them in its ``register(registry)``, exactly as a plugin does (``docs/own-leaves.md``)."""

from __future__ import annotations

from bt_grasp.tree.builtins import actions, conditions, controls, decorators, loops
from bt_grasp.tree.reasons import builtin_reasons
from bt_grasp.tree.registry import NodeRegistry

#: the built-in families, each with its ``register(registry)`` (SubTree is handled by the loader, not registered)
FAMILIES = (controls, decorators, loops, actions, conditions)


def register_builtins(registry: NodeRegistry) -> None:
    for family in FAMILIES:
        family.register(registry)


def builtin_registry() -> NodeRegistry:
    """A registry holding BT.CPP's built-in nodes and bt_grasp's built-in failure reasons (assembled here, where
    the built-ins live, so that the registry module never imports them)."""
    registry = NodeRegistry(reasons=builtin_reasons())
    register_builtins(registry)
    return registry


def builtin_names() -> frozenset[str]:
    """The IDs of the built-in nodes (``tree models`` leaves them out unless asked)."""
    return frozenset(builtin_registry().names())


#: BT.CPP 3.x names that 4.x removed, with the replacement to suggest
REMOVED_V3_NAMES: dict[str, str] = {
    "SequenceStar": "SequenceWithMemory",
    "FallbackStar": "Fallback",
    "ReactiveFallbackStar": "ReactiveFallback",
    "BlackboardCheckInt": "Precondition or ScriptCondition",
    "BlackboardCheckDouble": "Precondition or ScriptCondition",
    "BlackboardCheckString": "Precondition or ScriptCondition",
    "RetryUntilSuccesful": "RetryUntilSuccessful",
}
