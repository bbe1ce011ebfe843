"""Built-in conditions: ScriptCondition (BT.CPP's) and FailureIs (bt_grasp's)."""

from __future__ import annotations

from py_trees.common import Status

from bt_grasp.tree.builtins.actions import CODE_PORT, ScriptLeaf
from bt_grasp.tree.builtins.manifest import IN, condition
from bt_grasp.tree.leaf import FAILED_LEAF_KEY, FAILURE_REASON_KEY, Leaf
from bt_grasp.tree.registry import PortSpec


class ScriptCondition(ScriptLeaf):
    """SUCCESS when ``code`` evaluates to true, FAILURE otherwise."""

    def update(self) -> Status:
        return Status.SUCCESS if self.program().truth(self.blackboard, self._bt_enums) else Status.FAILURE


class FailureIs(Leaf):
    """SUCCESS when the last :meth:`Leaf.fail` reason (root blackboard ``failure_reason``) is ``reason``
    (and, when ``leaf`` is given, the failing leaf had that name)."""

    def update(self) -> Status:
        root = self.blackboard.root
        reason = root.get(FAILURE_REASON_KEY, None)
        wanted_leaf = str(self.ports.get("leaf"))
        if reason != self.ports.get("reason"):
            return Status.FAILURE
        if wanted_leaf and root.get(FAILED_LEAF_KEY, None) != wanted_leaf:
            return Status.FAILURE
        return Status.SUCCESS


SPECS = (
    condition(ScriptCondition, "SUCCESS if the script is true.", (CODE_PORT,)),
    condition(
        FailureIs,
        "SUCCESS when the last leaf failure had this reason.",
        (
            PortSpec("reason", IN, str, description="a failure reason such as NO_DETECTION", reason=True),
            PortSpec("leaf", IN, str, "", "only when this leaf (by name) failed"),
        ),
    ),
)
