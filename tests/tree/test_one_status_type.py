"""One status type for every node (issue 38, finding 4): a leaf returns BT.CPP's statuses, SKIPPED included, as
controls and decorators do; a halted leaf's ``terminate`` gets IDLE; ``failure_reason``/``failed_leaf`` leave the
blackboard once the tree succeeds. On main as it was a leaf returned py_trees' ``Status`` (no SKIPPED: "update()
returned ..., not SUCCESS/FAILURE/RUNNING"), and a recovered failure stayed on the blackboard after SUCCESS."""

from __future__ import annotations

import pytest
from py_trees.common import Status as PyTreesStatus

from bt_grasp.nodes import Leaf, NodeRegistry, Status, action, input_port
from bt_grasp.tree import builtin_registry, load_tree_from_string
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.introspect import bt_status_name


@action(ports=[input_port("skip", bool, False, "skip instead of acting")])
class MaybeSkip(Leaf):
    """SKIPPED when told to, else SUCCESS."""

    def update(self) -> Status:
        return Status.SKIPPED if self.ports.require("skip", bool) else Status.SUCCESS


@action()
class NoGoal(Leaf):
    """Fails with a reason."""

    def update(self) -> Status:
        return self.fail("NO_DETECTION", "nothing on the table")


@action()
class OldStyle(Leaf):
    """Returns py_trees' status, as leaves did before."""

    def update(self) -> Status:
        return PyTreesStatus.SUCCESS  # type: ignore[return-value]


def _registry() -> NodeRegistry:
    registry = builtin_registry()
    for node in (MaybeSkip, NoGoal, OldStyle):
        registry.register(node)
    return registry


def _tree(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


def test_a_leaf_returns_skipped_as_bt_cpp_leaves_may() -> None:
    tree = load_tree_from_string(_tree('<Sequence><MaybeSkip name="A" skip="true"/><MaybeSkip name="B"/></Sequence>'),
                                 _registry())
    # tick 1: A SKIPPED (stays IDLE, shown SKIPPED), B SUCCESS -> the Sequence SUCCESS (not every child skipped)
    assert tree.tick() is Status.SUCCESS
    assert bt_status_name(tree.find("A")) == "SKIPPED" and tree.find("A").bt_state is Status.IDLE
    only = load_tree_from_string(_tree('<Sequence><MaybeSkip skip="true"/></Sequence>'), _registry())
    # tick 1: the only child SKIPPED -> the Sequence SKIPPED, as BT.CPP's
    assert only.tick() is Status.SKIPPED


def test_a_py_trees_status_names_the_one_status_type() -> None:
    tree = load_tree_from_string(_tree("<OldStyle/>"), _registry())
    with pytest.raises(TreeRuntimeError, match=r"update\(\) returned py_trees' Status.SUCCESS; return "
                                               r"bt_grasp.nodes.Status.SUCCESS \(one status type for every node\)"):
        tree.tick()


def test_failure_reason_and_failed_leaf_are_cleared_when_the_tree_succeeds() -> None:
    tree = load_tree_from_string(_tree(
        '<Sequence><Fallback><NoGoal/><FailureIs reason="NO_DETECTION"/></Fallback>'
        '<ScriptCondition code="failure_reason == \'NO_DETECTION\'"/></Sequence>'), _registry())
    # tick 1: NoGoal FAILURE (failure_reason, failed_leaf written), FailureIs SUCCESS, the script still reads the
    # reason inside the tick: SUCCESS -> the tree succeeded: both keys removed
    assert tree.tick() is Status.SUCCESS
    assert "failure_reason" not in tree.blackboard_values() and "failed_leaf" not in tree.blackboard_values()
    assert tree.find("NoGoal").failure_reason == "NO_DETECTION"  # type: ignore[attr-defined]  # the node keeps it


def test_they_stay_when_the_tree_fails() -> None:
    tree = load_tree_from_string(_tree("<Sequence><NoGoal/></Sequence>"), _registry())
    # tick 1: NoGoal FAILURE -> the tree FAILURE: the reason is what the run ended with
    assert tree.tick() is Status.FAILURE
    assert tree.blackboard_values()["failure_reason"] == "NO_DETECTION"
    assert tree.blackboard_values()["failed_leaf"] == "NoGoal"
