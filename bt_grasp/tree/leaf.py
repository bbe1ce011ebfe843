"""Base class of every leaf (action or condition): py_trees' lifecycle with BT.CPP's halting.

A leaf is written like any py_trees behaviour::

    class Approach(Leaf):
        def setup(self, **kwargs):            # robot, camera, planner ... (never in __init__)
            self.robot = kwargs["robot"]
        def initialise(self):                 # one attempt starts (the leaf was not RUNNING)
            self.goal = self.ports.get("target")
        def update(self):                     # once per tick, never blocks
            if self.robot.reached(self.goal):
                return Status.SUCCESS
            if self.robot.stalled():
                return self.fail("BLOCKED", "the arm stopped before reaching the target")
            return Status.RUNNING
        def terminate(self, new_status):      # SUCCESS/FAILURE, or INVALID when halted while RUNNING
            if new_status == Status.INVALID:
                self.robot.stop()

A tick calls ``initialise()`` when the leaf was not RUNNING, then ``update()``; a finished update (SUCCESS or
FAILURE) is followed by ``terminate(new_status)``. When a parent halts a RUNNING leaf (ReactiveSequence,
Timeout, ``_while``) ``terminate(Status.INVALID)`` is called and the leaf returns to IDLE.

A leaf whose spec ``needs_robot`` does one control period of work per tick: when a wake-up re-run of the
root (see :class:`bt_grasp.tree.node.WakeUp`) reaches it again within the same control period while it is
RUNNING, it answers RUNNING without calling ``update()``; the robot moves only between periods anyway.
"""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import FROM_PY, BtNode, BtStatus
from bt_grasp.tree.reasons import ReasonLike, reason_name

#: root blackboard keys :meth:`Leaf.fail` writes (read by the ``FailureIs`` condition)
FAILURE_REASON_KEY = "failure_reason"
FAILED_LEAF_KEY = "failed_leaf"


class Leaf(BtNode):
    """A leaf node. Subclasses override ``setup``, ``initialise``, ``update`` and ``terminate``."""

    def __init__(self, ctx: NodeContext) -> None:
        py_trees.behaviour.Behaviour.__init__(self, ctx.name)
        self._bt_bind(ctx)
        self.ctx = ctx
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard
        #: why the last attempt failed, as a name such as "NO_DETECTION"; None otherwise
        self.failure_reason: str | None = None
        self._bt_once_per_period = ctx.spec.needs_robot
        self._bt_updated_in = -1

    def fail(self, reason: ReasonLike, sentence: str) -> Status:
        """Report a typed failure: sets ``failure_reason`` (the reason's name: a built-in
        :class:`~bt_grasp.tree.reasons.FailureReason`, or a :class:`~bt_grasp.tree.reasons.Reason` a plugin
        registered) and ``feedback_message``, and writes ``failure_reason`` and ``failed_leaf`` into the root
        blackboard. Returns ``Status.FAILURE``."""
        reason = reason_name(reason)
        self.failure_reason = reason
        self.feedback_message = sentence
        root = self.blackboard.root
        root.set(FAILURE_REASON_KEY, reason)
        root.set(FAILED_LEAF_KEY, self.name)
        return Status.FAILURE

    def bt_tick(self) -> BtStatus:
        period = self._bt_wake_up.period
        if self.bt_state is not BtStatus.RUNNING:
            self.failure_reason = None
            self.initialise()
        elif self._bt_once_per_period and self._bt_updated_in == period:
            return BtStatus.RUNNING  # a wake-up re-run within the same control period: no second update
        self._bt_updated_in = period
        new_status = self.update()
        result = FROM_PY.get(new_status) if isinstance(new_status, Status) else None
        if result is None:
            raise TreeRuntimeError(f"{self.bt_path}: update() returned {new_status!r}, not SUCCESS/FAILURE/RUNNING")
        if result is not BtStatus.RUNNING:
            self.terminate(new_status)
        return result

    def halt(self) -> None:
        if self.bt_state is BtStatus.RUNNING:
            self.terminate(Status.INVALID)
        self.reset_status()
