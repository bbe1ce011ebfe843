"""Every built-in node type, with BT.CPP v4's registration IDs and port names, one module per family
(as BT.CPP's ``src/controls``, ``src/decorators``, ``src/actions``): each module declares its ``SPECS``."""

from __future__ import annotations

from bt_grasp.tree.builtins import actions, conditions, controls, decorators, loops
from bt_grasp.tree.reasons import builtin_reasons
from bt_grasp.tree.registry import NodeRegistry, NodeSpec


def builtin_specs() -> tuple[NodeSpec, ...]:
    """The specs :func:`register_builtins` adds (SubTree is handled by the loader, not registered)."""
    return controls.SPECS + decorators.SPECS + loops.SPECS + actions.SPECS + conditions.SPECS


def register_builtins(registry: NodeRegistry) -> None:
    for spec in builtin_specs():
        registry.register(spec)


def builtin_registry() -> NodeRegistry:
    """A registry holding BT.CPP's built-in nodes and bt_grasp's built-in failure reasons (assembled here, where
    the built-ins live, so that the registry module never imports them)."""
    registry = NodeRegistry(reasons=builtin_reasons())
    register_builtins(registry)
    return registry


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
