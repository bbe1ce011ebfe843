"""Base class of every leaf (action or condition): py_trees' lifecycle with BT.CPP's statuses and halting.

A leaf is declared and written like this (``bt_grasp.nodes`` has every name)::

    @action(ports=[input_port("target", Pose, description="where to go")], needs_robot=True, reasons=[BLOCKED])
    class Approach(RobotLeaf):
        '''Moves the tool to the target.'''

        def initialise(self) -> None:         # one attempt starts (the leaf was not RUNNING)
            self.goal = self.ports.require("target", Pose)
        def update(self) -> Status:            # once per tick, never blocks
            if self.cell.robot.stalled():
                return self.fail(BLOCKED, "the arm stopped before reaching the target")
            return Status.SUCCESS if self.reached(self.goal) else Status.RUNNING
        def terminate(self, new_status: Status) -> None:   # SUCCESS/FAILURE, or IDLE when halted
            if new_status is Status.IDLE:
                self.cell.robot.stop()

A tick calls ``initialise()`` when the leaf was not RUNNING, then ``update()``, which returns one
:class:`~bt_grasp.tree.node.BtStatus` (``Status`` in ``bt_grasp.nodes``): RUNNING, SUCCESS, FAILURE or SKIPPED.
A completed update (SUCCESS or FAILURE) is followed by ``terminate(new_status)``; SKIPPED is returned to the
parent and the leaf stays as it was (BT.CPP stores no SKIPPED). When a parent halts a RUNNING leaf
(ReactiveSequence, Timeout, ``_while``) ``terminate(Status.IDLE)`` is called and the leaf returns to IDLE.

A leaf whose declaration ``needs_robot`` does one control period of work per tick: when a wake-up re-run of the
root (see :class:`bt_grasp.tree.node.WakeUp`) reaches it again within the same control period while it is
RUNNING, it answers RUNNING without calling ``update()``; the robot moves only between periods anyway.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import TYPE_CHECKING

from py_trees.common import Status as PyTreesStatus

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.reasons import FAILED_LEAF_KEY, FAILURE_REASON_KEY, ReasonLike, reason_name

if TYPE_CHECKING:
    from bt_grasp.clock import Clock
    from bt_grasp.tree.blackboard import Blackboard
    from bt_grasp.tree.context import NodeContext
    from bt_grasp.tree.ports import PortAccessor

__all__ = ["FAILED_LEAF_KEY", "FAILURE_REASON_KEY", "Leaf", "SimpleLeaf", "SimpleTick"]


class Leaf(BtNode):
    """A leaf node. Subclasses override ``setup``, ``initialise``, ``update`` and ``terminate``.

    Attributes:
        name: the instance name (the ``name`` attribute in the tree file, else the registration ID)
        ctx: the :class:`~bt_grasp.tree.context.NodeContext` it was built from (its file, line, path, spec)
        ports: read inputs (``ports.get``, ``ports.require``, ``ports.has``), write outputs (``ports.set``)
        clock: simulated time (never read the wall clock)
        blackboard: the blackboard of the tree (or SubTree) instance the leaf is in
        failure_reason: why the last attempt failed (a reason's name such as "NO_DETECTION"), else None
    """

    ctx: NodeContext
    ports: PortAccessor
    clock: Clock
    blackboard: Blackboard

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx.name)
        self._bt_bind(ctx)
        self.ctx = ctx
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard
        self.failure_reason: str | None = None
        self._bt_once_per_period = ctx.spec.needs_robot
        self._bt_updated_in = -1

    # ---- what a leaf provides (py_trees' lifecycle, BT.CPP's statuses) --------------------------------------
    def initialise(self) -> None:
        """One attempt starts (the leaf was not RUNNING): BT.CPP's ``onStart``."""

    @abc.abstractmethod
    def update(self) -> BtStatus:
        """One tick of work: RUNNING, SUCCESS, FAILURE or SKIPPED (BT.CPP's ``tick``/``onRunning``); a leaf
        class without it cannot be built (a load error naming the plugin)."""

    def terminate(self, new_status: BtStatus) -> None:
        """After a completed update (SUCCESS or FAILURE), or with IDLE when halted while RUNNING
        (BT.CPP's ``onHalted``)."""

    def fail(self, reason: ReasonLike, sentence: str) -> BtStatus:
        """Report a typed failure: sets ``failure_reason`` (the reason's name: a built-in
        :class:`~bt_grasp.tree.reasons.FailureReason`, or a :class:`~bt_grasp.tree.reasons.Reason` a plugin
        declared) and ``feedback_message``, and writes ``failure_reason`` and ``failed_leaf`` into the root
        blackboard (cleared when the whole tree succeeds). Returns FAILURE."""
        name = reason_name(reason)
        self.failure_reason = name
        self.feedback_message = sentence
        root = self.blackboard.root
        root.set(FAILURE_REASON_KEY, name)
        root.set(FAILED_LEAF_KEY, self.name)
        return BtStatus.FAILURE

    # ---- BT.CPP's machinery ---------------------------------------------------------------------------------
    def bt_tick(self) -> BtStatus:
        period = self._bt_wake_up.period
        if self.bt_state is not BtStatus.RUNNING:
            self.failure_reason = None
            self.initialise()
        elif self._bt_once_per_period and self._bt_updated_in == period:
            return BtStatus.RUNNING  # a wake-up re-run within the same control period: no second update
        self._bt_updated_in = period
        result = self._checked(self.update())
        if result.completed:
            self.terminate(result)
        return result

    def _checked(self, result: object) -> BtStatus:
        if isinstance(result, BtStatus) and result is not BtStatus.IDLE:
            return result
        if isinstance(result, PyTreesStatus):
            name = "IDLE" if result is PyTreesStatus.INVALID else result.name
            raise TreeRuntimeError(f"{self.bt_path}: update() returned py_trees' Status.{result.name}; return "
                                   f"bt_grasp.nodes.Status.{name} (one status type for every node)")
        raise TreeRuntimeError(f"{self.bt_path}: update() returned {result!r}, not RUNNING, SUCCESS, FAILURE or "
                               "SKIPPED")

    def halt(self) -> None:
        if self.bt_state is BtStatus.RUNNING:
            self.terminate(BtStatus.IDLE)
        self.reset_status()

    def failed(self, reason: ReasonLike, sentence: str) -> BtStatus:
        """Gone: one way to fail for every leaf."""
        raise TreeRuntimeError(f"{self.bt_path}: failed(...) is now fail(...), for every leaf")


#: what :meth:`~bt_grasp.tree.registry.NodeRegistry.register_simple_action` takes: ``tick(node) -> Status``
SimpleTick = Callable[[Leaf], BtStatus]


class SimpleLeaf(Leaf):
    """A leaf made of a function (BT.CPP's ``SimpleActionNode``/``SimpleConditionNode``): ``tick(self)`` is its
    ``update``. A synchronous one (a simple action, as BT.CPP's ``SyncActionNode``) may not return RUNNING."""

    def __init__(self, ctx: NodeContext, *, tick: SimpleTick, synchronous: bool) -> None:
        super().__init__(ctx)
        self._tick = tick
        self._synchronous = synchronous

    def update(self) -> BtStatus:
        result = self._checked(self._tick(self))
        if result is BtStatus.RUNNING and self._synchronous:
            raise TreeRuntimeError(f"{self.bt_path}: a simple action must never return RUNNING (BT.CPP's "
                                   "SyncActionNode); declare a class with @action for a leaf that runs over ticks")
        return result
