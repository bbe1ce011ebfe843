"""Built-in conditions: ScriptCondition (BT.CPP's) and FailureIs (bt_grasp's), declared with ``@condition`` and
registered by :func:`register`, as a plugin's are."""

from __future__ import annotations

from bt_grasp.tree.builtins.actions import ScriptLeaf, code_port
from bt_grasp.tree.node_api import Leaf, NodeRegistry, Status, condition, input_port
from bt_grasp.tree.reasons import FAILED_LEAF_KEY, FAILURE_REASON_KEY


@condition(ports=[code_port()], description="SUCCESS if the script is true.")
class ScriptCondition(ScriptLeaf):
    """SUCCESS when ``code`` evaluates to true, FAILURE otherwise."""

    def update(self) -> Status:
        return Status.SUCCESS if self.program().truth(self.blackboard, self.enums) else Status.FAILURE


@condition(
    ports=[
        input_port("reason", str, description="a failure reason such as NO_DETECTION", required=True, reason=True),
        input_port("leaf", str, "", "only when this leaf (by name) failed"),
    ],
    description="SUCCESS when the last leaf failure had this reason.",
)
class FailureIs(Leaf):
    """SUCCESS when the last :meth:`Leaf.fail` reason (root blackboard ``failure_reason``) is ``reason``
    (and, when ``leaf`` is given, the failing leaf had that name)."""

    def update(self) -> Status:
        root = self.blackboard.root
        reason = root.get(FAILURE_REASON_KEY, None)
        wanted_leaf = self.ports.require("leaf", str)
        if reason != self.ports.require("reason", str):
            return Status.FAILURE
        if wanted_leaf and root.get(FAILED_LEAF_KEY, None) != wanted_leaf:
            return Status.FAILURE
        return Status.SUCCESS


NODES: tuple[type[Leaf], ...] = (ScriptCondition, FailureIs)


def register(registry: NodeRegistry) -> None:
    """The built-in conditions, registered as a plugin registers its nodes."""
    for node in NODES:
        registry.register(node)
