"""BT.CPP's node execution (``TreeNode::executeTick``, ``haltNode``) on top of py_trees behaviours.

Every node a tree file builds is a :class:`BtNode`: a py_trees behaviour (a ``Composite``, ``Decorator`` or
plain ``Behaviour``) that parents tick through :meth:`BtNode.execute_tick`, so BT.CPP's statuses and rules
hold exactly:

* the BT.CPP status lives in ``bt_state`` (IDLE, RUNNING, SUCCESS, FAILURE); py_trees' ``status`` mirrors it,
  with IDLE shown as ``Status.INVALID``;
* SKIPPED is returned to the parent but never stored (BT.CPP keeps the node IDLE). A consumer reads it as
  ``node.bt_status_extra == "SKIPPED"``: the node's most recent tick was skipped and it was not ticked since.
  ``bt_status_extra`` is ``"IDLE"`` for a node reset to IDLE, and None while ``status`` says it all;
* pre-conditions (``_failureIf``, ``_successIf``, ``_skipIf``, ``_while``) are checked only while the node is
  IDLE, except ``_while``, which halts a RUNNING node when it turns false (the node returns SKIPPED);
  post-conditions run when the node completes (``_onSuccess``/``_onFailure`` then ``_post``), and
  ``_onHalted`` after a halt;
* halting (BT.CPP ``haltChild``) calls ``halt_node`` on RUNNING children, which reaches a leaf's
  ``terminate(Status.IDLE)``.

``tick()`` (the py_trees generator) ticks the node as a tree root, as BT.CPP's ``Tree::tickOnce``: it resets
a completed root to IDLE first, executes the root, and executes it again at once while the root is RUNNING
and a node requested a wake-up (:class:`WakeUp`; Repeat, RetryUntilSuccessful, SequenceWithMemory,
AsyncSequence and AsyncFallback do after each synchronous child). When the root ends in SUCCESS, the root
blackboard's ``failure_reason`` and ``failed_leaf`` (a leaf's :meth:`fail` wrote them) are removed: the tree
recovered from that failure. It then yields every node, so ``py_trees.trees.BehaviourTree`` with visitors works
unchanged.
"""

from __future__ import annotations

import enum
import os
import sys
import traceback
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import py_trees
from py_trees.common import Status

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.kinds import NodeKind
from bt_grasp.tree.reasons import FAILED_LEAF_KEY, FAILURE_REASON_KEY

#: this package's folder: frames inside it are bt_grasp's, not a plugin's
_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep

if TYPE_CHECKING:
    import uuid

    from bt_grasp.tree.blackboard import Blackboard
    from bt_grasp.tree.context import NodeContext
    from bt_grasp.tree.registry import NodeSpec
    from bt_grasp.tree.scripting import Program

    class PyTreesBehaviour:
        """py_trees' ``Behaviour`` as the type checker sees a bt_grasp node: every attribute and method bt_grasp
        uses, but not ``update`` and ``terminate``, which a bt_grasp leaf redefines with BT.CPP's statuses (one
        status type for every node). py_trees never calls them on a bt_grasp node (:meth:`BtNode.tick` and
        ``execute_tick`` drive it), so the only thing hidden is a signature the node never meets. At run time the
        base is py_trees' own class (below)."""

        id: uuid.UUID
        name: str
        status: Status
        feedback_message: str
        parent: py_trees.behaviour.Behaviour | None
        children: list[py_trees.behaviour.Behaviour]

        def __init__(self, name: str) -> None: ...
        def setup(self, **kwargs: object) -> None: ...
        def initialise(self) -> None: ...
        def shutdown(self) -> None: ...
        def iterate(self, direct_descendants: bool = False) -> Iterator[py_trees.behaviour.Behaviour]: ...
        def tick(self) -> Iterator[py_trees.behaviour.Behaviour]: ...
        def stop(self, new_status: Status = Status.INVALID) -> None: ...
else:
    PyTreesBehaviour = py_trees.behaviour.Behaviour


class BtStatus(enum.Enum):
    """BT.CPP's ``NodeStatus``: the one status type of every node (``Status`` in :mod:`bt_grasp.nodes`). A leaf's
    ``update()`` and a control's or decorator's ``bt_tick()`` return RUNNING, SUCCESS, FAILURE or SKIPPED; IDLE is
    the state of a node that is not running (and what ``terminate`` receives when a leaf is halted)."""

    IDLE = "IDLE"
    RUNNING = "RUNNING"
    SUCCESS = "SUCCESS"
    FAILURE = "FAILURE"
    SKIPPED = "SKIPPED"

    @property
    def completed(self) -> bool:
        return self is BtStatus.SUCCESS or self is BtStatus.FAILURE


TO_PY: dict[BtStatus, Status] = {
    BtStatus.IDLE: Status.INVALID,
    BtStatus.RUNNING: Status.RUNNING,
    BtStatus.SUCCESS: Status.SUCCESS,
    BtStatus.FAILURE: Status.FAILURE,
}
FROM_PY: dict[Status, BtStatus] = {
    Status.RUNNING: BtStatus.RUNNING,
    Status.SUCCESS: BtStatus.SUCCESS,
    Status.FAILURE: BtStatus.FAILURE,
}

#: BT.CPP's evaluation order of pre-conditions and post-conditions
PRE_CONDITIONS: tuple[str, ...] = ("_failureIf", "_successIf", "_skipIf", "_while")
POST_CONDITIONS: tuple[str, ...] = ("_onHalted", "_onFailure", "_onSuccess", "_post")


@dataclass(frozen=True)
class Conditions:
    """A node's parsed pre/post-condition scripts, keyed by attribute name (``_skipIf``)."""

    scripts: Mapping[str, Program] = field(default_factory=dict)

    @property
    def pre(self) -> tuple[tuple[str, Program], ...]:
        return tuple((k, self.scripts[k]) for k in PRE_CONDITIONS if k in self.scripts)

    def get(self, key: str) -> Program | None:
        return self.scripts.get(key)


NO_CONDITIONS = Conditions()

#: a control period executes the root at most this many times (wake-up re-runs included); further wake-ups
#: wait for the next period
WAKE_UP_LIMIT = 10_000


class WakeUp:
    """BT.CPP's ``WakeUpSignal`` shared by the nodes of one tree, plus the control-period counter.

    ``emit`` is BT.CPP's ``emitWakeUpSignal``; ``take`` reads and clears the flag (``waitFor(0)``).
    ``period`` counts control periods (CLI ticks); ``runs`` the root executions in the current one;
    ``capped`` says the current one stopped at :data:`WAKE_UP_LIMIT` with a wake-up still requested (by
    ``requester``).
    """

    __slots__ = ("capped", "pending", "period", "requester", "runs")

    def __init__(self) -> None:
        self.capped = False
        self.pending = False
        self.requester = ""
        self.period = 0
        self.runs = 0

    def emit(self, node: BtNode) -> None:
        self.pending = True
        self.requester = f"{node.bt_type} '{node.bt_path}'"

    def take(self) -> bool:
        pending, self.pending = self.pending, False
        return pending


class BtNode(PyTreesBehaviour):
    """Base of every node built from a tree file (a py_trees ``Behaviour``). Subclasses implement :meth:`bt_tick`
    (and ``halt``)."""

    bt_uid: int = 0
    bt_type: str = ""
    bt_path: str = ""
    bt_kind: NodeKind = NodeKind.ACTION
    bt_status_extra: str | None = "IDLE"
    bt_state: BtStatus = BtStatus.IDLE
    #: the spec the node was built from (on a node class: its declaration, stored by ``@action`` and the like)
    bt_spec: NodeSpec

    def _bt_bind(self, ctx: NodeContext) -> None:
        """Copy identity and conditions from the build context (called by every ``__init__``)."""
        self.bt_uid = ctx.uid
        self.bt_type = ctx.type_id
        self.bt_path = ctx.path
        self.bt_kind = ctx.kind
        self.bt_spec = ctx.spec
        #: ``file:line: `` of the node's declaration, for tick errors ("" when unknown)
        self.bt_where = f"{ctx.source}:{ctx.line}: " if ctx.source and ctx.line else ""
        #: the attributes exactly as written in the tree file (ports, name, pre/post conditions)
        self.bt_attributes: dict[str, str] = dict(ctx.attributes)
        self.bt_state = BtStatus.IDLE
        self.bt_status_extra = "IDLE"
        #: called after every executeTick as ``listener(node, status_before, result)`` (runners, recorders)
        self.bt_listener: Callable[[BtNode, BtStatus, BtStatus], None] | None = None
        #: called on every change of the stored status as ``hook(node, previous, new)``, halts and resets to IDLE
        #: included: BT.CPP's ``subscribeToStatusChange`` (what its StatusChangeLogger and Groot2's log watch)
        self.bt_on_change: Callable[[BtNode, BtStatus, BtStatus], None] | None = None
        #: called just before the node's own tick runs (after its pre-conditions let it), as ``hook(node)``:
        #: where BT.CPP has ``setPreTickFunction``; fault injectors watch leaf entries here
        self.bt_pre_tick: Callable[[BtNode], None] | None = None
        self._bt_blackboard: Blackboard = ctx.blackboard
        self._bt_enums: Mapping[str, int] = ctx.enums
        self._bt_conditions: Conditions = ctx.conditions
        self._bt_pre = ctx.conditions.pre
        self._bt_has_post = any(k in ctx.conditions.scripts for k in POST_CONDITIONS[1:])
        self._bt_wake_up: WakeUp = ctx.wake_up

    # ---- what subclasses provide ------------------------------------------------------------------
    def bt_tick(self) -> BtStatus:
        """One tick of the node's own logic (BT.CPP ``tick()``)."""
        raise NotImplementedError

    def halt(self) -> None:
        """Stop the node's activity and return to IDLE (BT.CPP ``halt()``)."""
        self.reset_status()

    # ---- BT.CPP's TreeNode machinery --------------------------------------------------------------
    def execute_tick(self) -> BtStatus:
        """BT.CPP ``executeTick``: pre-conditions, ``bt_tick``, post-conditions, store the status. A tick error
        is reported once, by the innermost node, with its file, line, type and path (BT.CPP's
        ``NodeExecutionError``)."""
        before = self.bt_state
        try:
            result: BtStatus | None = self._check_preconditions() if self._bt_pre else None
            if result is None:
                if self.bt_pre_tick is not None:
                    self.bt_pre_tick(self)
                result = self.bt_tick()
            if self._bt_has_post and result.completed:
                self._run_postconditions(result)
        except TreeRuntimeError as exc:
            if exc.located:
                raise
            message = str(exc).removeprefix(f"{self.bt_path}: ")
            raise TreeRuntimeError(f"{self.bt_where}{self.bt_type} '{self.bt_path}': {message}", located=True) from None
        except Exception as exc:
            if not self._bt_is_plugin():
                raise
            raise self._bt_plugin_error(exc) from exc
        if result is BtStatus.SKIPPED:
            self.bt_status_extra = "SKIPPED"
        else:
            self.set_bt_status(result)
        if self.bt_listener is not None:
            self.bt_listener(self, before, result)
        return result

    def _bt_is_plugin(self) -> bool:
        """True for a node whose class comes from outside bt_grasp (a user's plugin)."""
        module = type(self).__module__
        return not (module == "bt_grasp" or module.startswith("bt_grasp."))

    def _bt_plugin_error(self, exc: Exception) -> TreeRuntimeError:
        """A plugin node's own exception as one located sentence: the tree's file and line, the node, what
        was raised and where in the plugin (its innermost frame outside bt_grasp)."""
        module_file = getattr(sys.modules.get(type(self).__module__), "__file__", None)
        frames = [f for f in traceback.extract_tb(exc.__traceback__) if not f.filename.startswith(_PACKAGE_DIR)]
        own = [f for f in frames if module_file is not None and f.filename == module_file]
        chosen = own or frames
        where = f" at {chosen[-1].filename}:{chosen[-1].lineno}" if chosen else ""
        return TreeRuntimeError(
            f"{self.bt_where}{self.bt_type} '{self.bt_path}': the node's code raised "
            f"{type(exc).__name__}{where}: {exc}",
            located=True,
        )

    def set_bt_status(self, status: BtStatus) -> None:
        if status is BtStatus.IDLE or status is BtStatus.SKIPPED:
            raise ValueError("use reset_status() to make a node IDLE; SKIPPED is never stored")
        previous, self.bt_state = self.bt_state, status
        self.status = TO_PY[status]
        self.bt_status_extra = None
        if previous is not status and self.bt_on_change is not None:
            self.bt_on_change(self, previous, status)

    def reset_status(self) -> None:
        """BT.CPP ``resetStatus``: back to IDLE without halting (a SKIPPED marker survives)."""
        previous = self.bt_state
        if previous is not BtStatus.IDLE and self.bt_status_extra != "SKIPPED":
            self.bt_status_extra = "IDLE"
        self.bt_state = BtStatus.IDLE
        self.status = Status.INVALID
        if previous is not BtStatus.IDLE and self.bt_on_change is not None:
            self.bt_on_change(self, previous, BtStatus.IDLE)

    def halt_node(self) -> None:
        """BT.CPP ``haltNode``: ``halt()`` then the ``_onHalted`` script."""
        try:
            self.halt()
        except TreeRuntimeError:
            raise
        except Exception as exc:
            if not self._bt_is_plugin():
                raise
            raise self._bt_plugin_error(exc) from exc
        script = self._bt_conditions.get("_onHalted")
        if script is not None:
            script.run(self._bt_blackboard, self._bt_enums)

    def _check_preconditions(self) -> BtStatus | None:
        state = self.bt_state
        for key, script in self._bt_pre:
            if state is BtStatus.IDLE:
                if script.truth(self._bt_blackboard, self._bt_enums):
                    if key == "_failureIf":
                        return BtStatus.FAILURE
                    if key == "_successIf":
                        return BtStatus.SUCCESS
                    if key == "_skipIf":
                        return BtStatus.SKIPPED
                elif key == "_while":
                    return BtStatus.SKIPPED
            elif (
                state is BtStatus.RUNNING and key == "_while" and not script.truth(self._bt_blackboard, self._bt_enums)
            ):
                self.halt_node()
                return BtStatus.SKIPPED
        return None

    def _run_postconditions(self, status: BtStatus) -> None:
        scripts = self._bt_conditions
        key = "_onSuccess" if status is BtStatus.SUCCESS else "_onFailure"
        for name in (key, "_post"):
            script = scripts.get(name)
            if script is not None:
                script.run(self._bt_blackboard, self._bt_enums)

    def bt_children(self) -> list[BtNode]:
        """The children, as bt_grasp nodes (every child of a bt_grasp node is one)."""
        return [child for child in self.children if isinstance(child, BtNode)]

    @property
    def enums(self) -> Mapping[str, int]:
        """The registry's scripting enums (BT.CPP's ``config().enums``), for a node that runs scripts."""
        return self._bt_enums

    # ---- py_trees integration ---------------------------------------------------------------------
    @property
    def bt_wake_up(self) -> WakeUp:
        """The tree's shared wake-up signal and control-period counter."""
        return self._bt_wake_up

    def emit_wake_up(self) -> None:
        """Ask the tree to execute the root again within this control period (BT.CPP ``emitWakeUpSignal``)."""
        self._bt_wake_up.emit(self)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Tick this node as the root of a tree for one control period (BT.CPP ``tickOnce``), then yield every
        node (for py_trees visitors). At most :data:`WAKE_UP_LIMIT` root executions happen in one period: a
        wake-up requested after that is left to the next period (the root stays RUNNING), so an endless
        synchronous loop (``Repeat num_cycles="-1"`` over a child that never runs) advances period by period
        and a ``Timeout`` around it ends it in simulated time, where BT.CPP's wall-clock timer would."""
        wake_up = self._bt_wake_up
        wake_up.period += 1
        if self.bt_state.completed:
            self.reset_status()
        status = self.execute_tick()
        runs = 1
        while status is BtStatus.RUNNING and runs < WAKE_UP_LIMIT and wake_up.take():
            status = self.execute_tick()
            runs += 1
        wake_up.capped = status is BtStatus.RUNNING and wake_up.take()
        wake_up.runs = runs
        if status is BtStatus.SUCCESS:  # the tree recovered from any failure a leaf reported on the way
            root_blackboard = self._bt_blackboard.root
            root_blackboard.unset(FAILURE_REASON_KEY)
            root_blackboard.unset(FAILED_LEAF_KEY)
        self.bt_last_root_status = status
        yield from self.iterate()

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """py_trees' interrupt (``BehaviourTree.interrupt``/``shutdown``): halt like BT.CPP."""
        if new_status == Status.INVALID:
            if self.bt_state is BtStatus.RUNNING:
                self.halt_node()
            self.reset_status()
        else:
            self.set_bt_status(FROM_PY[new_status])

    def __repr__(self) -> str:
        return f"<{self.bt_type} {self.bt_path!r} uid={self.bt_uid} {self.bt_state.value}>"


def as_behaviour(node: BtNode) -> py_trees.behaviour.Behaviour:
    """A bt_grasp node as py_trees' own type, for py_trees' constructors (it is one at run time; the type checker
    sees :class:`PyTreesBehaviour`)."""
    if not isinstance(node, py_trees.behaviour.Behaviour):  # pragma: no cover - BtNode's base is Behaviour
        raise TypeError(f"{node!r} is not a py_trees behaviour")
    return node


def describe(node: py_trees.behaviour.Behaviour) -> str:
    """``Type 'path'`` for messages."""
    return f"{getattr(node, 'bt_type', type(node).__name__)} {getattr(node, 'bt_path', node.name)!r}"
