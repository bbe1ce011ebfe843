"""BT.CPP 4.10 decorators, each following the corresponding ``src/decorators/*``: Inverter, ForceSuccess,
ForceFailure, RetryUntilSuccessful, Repeat, Timeout, Delay, KeepRunningUntilFailure, RunOnce, Precondition,
SkipUnlessUpdated and WaitValueUpdate (the Loop* family is in :mod:`bt_grasp.tree.builtins.loops`).
Timeout and Delay read the injected simulated clock, never the wall clock."""

from __future__ import annotations

import py_trees

from bt_grasp.tree.builtins.manifest import IN, STATUS_NAMES, decorator
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.ports import EntryWatch
from bt_grasp.tree.registry import PortSpec
from bt_grasp.tree.scripting import Program, parse_script

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    BtStatus.RUNNING,
    BtStatus.SUCCESS,
    BtStatus.FAILURE,
    BtStatus.SKIPPED,
    BtStatus.IDLE,
)


class Decorator(BtNode, py_trees.decorators.Decorator):
    """Base of decorators; ``halt`` resets the child (halting it when RUNNING) then itself."""

    def __init__(self, ctx: NodeContext) -> None:
        (child,) = ctx.children
        py_trees.decorators.Decorator.__init__(self, ctx.name, child)
        self._bt_bind(ctx)
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard  # the tree instance's, as a leaf's (BT.CPP ``config().blackboard``)
        self.child: BtNode = child  # type: ignore[assignment]

    def update(self) -> py_trees.common.Status:  # pragma: no cover - py_trees never calls it here
        return self.status

    def execute_tick(self) -> BtStatus:
        """BT.CPP ``DecoratorNode::executeTick``: a child left SUCCESS or FAILURE goes back to IDLE."""
        status = super().execute_tick()
        if self.child.bt_state.completed:
            self.child.reset_status()
        return status

    def tick_child(self) -> BtStatus:
        status = self.child.execute_tick()
        if status is IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: the child returned IDLE")
        return status

    def reset_child(self) -> None:
        self.halt_child(0)

    def halt(self) -> None:
        self.reset_child()
        self.reset_status()


class Inverter(Decorator):
    def bt_tick(self) -> BtStatus:
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            return FAILURE if status is SUCCESS else SUCCESS
        return status


class ForceSuccess(Decorator):
    _forced = SUCCESS

    def bt_tick(self) -> BtStatus:
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            return self._forced
        return status


class ForceFailure(ForceSuccess):
    _forced = FAILURE


class KeepRunningUntilFailure(Decorator):
    """RUNNING after each child success (the child starts again next tick); FAILURE when the child fails."""

    def bt_tick(self) -> BtStatus:
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            return FAILURE if status is FAILURE else RUNNING
        if status is SKIPPED:  # BT.CPP returns its own (RUNNING) status
            return RUNNING
        return status


class _Loop(Decorator):
    """RetryUntilSuccessful and Repeat (BT.CPP ``RetryNode``/``RepeatNode``).

    The child is ticked again after each ``_again`` status, up to ``_port`` times (-1: forever). When the
    child completed within the same tick it started in, the node yields: RUNNING plus a wake-up, so the
    tree executes the root again at once (an enclosing reactive parent re-checks its conditions); a child
    that had been RUNNING is restarted in the same tick.
    """

    _port = ""
    _again: BtStatus = FAILURE  # the status that makes the loop go round

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.count = 0

    def bt_tick(self) -> BtStatus:
        limit = int(self.ports.get(self._port))
        looping = self.count < limit or limit == -1
        self.set_bt_status(RUNNING)
        while looping:
            before = self.child.bt_state
            status = self.tick_child()
            if status is RUNNING:
                return RUNNING
            if status is SKIPPED:
                self.reset_child()
                return SKIPPED
            if status is not self._again:
                self.count = 0
                self.reset_child()
                return status
            self.count += 1
            limit = int(self.ports.get(self._port))
            looping = self.count < limit or limit == -1
            self.reset_child()
            if before is IDLE and looping:
                self.emit_wake_up()
                return RUNNING
        self.count = 0
        return SUCCESS if self._again is SUCCESS else FAILURE

    def halt(self) -> None:
        self.count = 0
        super().halt()


class RetryUntilSuccessful(_Loop):
    """Ticks the child again after each FAILURE, up to ``num_attempts`` attempts (-1: forever)."""

    _port = "num_attempts"
    _again = FAILURE


class Repeat(_Loop):
    """Ticks the child again after each SUCCESS, ``num_cycles`` times (-1: forever)."""

    _port = "num_cycles"
    _again = SUCCESS


class Timeout(Decorator):
    """Halts the RUNNING child and fails once ``msec`` of simulated time passed since it started
    (``msec`` 0: no limit). The time is checked when the node is ticked, once per control period."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.started = False
        self.start_ns = 0

    def bt_tick(self) -> BtStatus:
        msec = int(self.ports.get("msec"))
        now = self.clock.now_ns()
        if not self.started:
            self.started = True
            self.start_ns = now
            self.set_bt_status(RUNNING)
        elif msec > 0 and now - self.start_ns >= msec * 1_000_000 and self.child.bt_state is RUNNING:
            self.feedback_message = f"timed out after {msec} ms"
            self.halt_child(0)
            self.started = False
            return FAILURE
        status = self.tick_child()
        if status.completed:
            self.started = False
            self.reset_child()
        return status

    def halt(self) -> None:
        self.started = False
        super().halt()


class Delay(Decorator):
    """RUNNING until ``delay_msec`` of simulated time passed, then ticks the child."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.started = False
        self.start_ns = 0

    def bt_tick(self) -> BtStatus:
        delay_ns = int(self.ports.get("delay_msec")) * 1_000_000
        now = self.clock.now_ns()
        if not self.started:
            self.started = True
            self.start_ns = now
            self.set_bt_status(RUNNING)
        if now - self.start_ns < delay_ns:
            return RUNNING
        status = self.tick_child()
        if status.completed:
            self.started = False
            self.reset_child()
        return status

    def halt(self) -> None:
        self.started = False
        super().halt()


class RunOnce(Decorator):
    """Ticks the child until it completes once; afterwards SKIPPED (``then_skip``) or that same status.
    The memory survives halts and resets, as in BT.CPP."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.done: BtStatus | None = None

    def bt_tick(self) -> BtStatus:
        if self.done is not None:
            return SKIPPED if self.ports.get("then_skip") else self.done
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.done = status
            self.reset_child()
        return status


class Precondition(Decorator):
    """Ticks the child when the ``if`` script is true (checked when the child is not running yet);
    otherwise returns ``else`` (FAILURE by default)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.child_running = False
        self._program: Program | None = None
        if ctx.ports.key("if") is None:
            self._program = parse_script(ctx.ports.get("if"))

    def _script(self) -> Program:
        if self._program is not None:
            return self._program
        try:
            return parse_script(str(self.ports.get("if")))
        except ScriptSyntaxError as exc:
            raise TreeRuntimeError(f"{self.bt_path}: {exc}") from None

    def bt_tick(self) -> BtStatus:
        otherwise = BtStatus(self.ports.get("else"))
        if not self.child_running:
            self.child_running = self._script().truth(self._bt_blackboard, self._bt_enums)
        if not self.child_running:
            return otherwise
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            self.child_running = False
        return status

    def halt(self) -> None:
        self.child_running = False
        super().halt()


class _EntryUpdated(Decorator):
    """SkipUnlessUpdated / WaitValueUpdate (BT.CPP ``EntryUpdatedDecorator``): the child is ticked only when
    the entry was written since this node last looked (a RUNNING child is resumed regardless)."""

    _not_updated: BtStatus = SKIPPED

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.watch = EntryWatch(ctx.attributes.get("entry", ""))
        self.child_running = False

    def bt_tick(self) -> BtStatus:
        if not self.child_running and not self.watch.written_since(self._bt_blackboard):
            return self._not_updated
        status = self.tick_child()
        self.child_running = status is RUNNING
        return status

    def halt(self) -> None:
        self.child_running = False
        super().halt()


class SkipUnlessUpdated(_EntryUpdated):
    _not_updated = SKIPPED


class WaitValueUpdate(_EntryUpdated):
    _not_updated = RUNNING


_ENTRY = PortSpec("entry", IN, object, description="the blackboard entry to watch ({key} or key)")

SPECS = (
    decorator(Inverter, "Swaps SUCCESS and FAILURE."),
    decorator(ForceSuccess, "SUCCESS whenever the child completes."),
    decorator(ForceFailure, "FAILURE whenever the child completes."),
    decorator(
        RetryUntilSuccessful,
        "Ticks the child again after a FAILURE, up to num_attempts times.",
        (PortSpec("num_attempts", IN, int, description="attempts before failing (-1: forever)"),),
    ),
    decorator(
        Repeat,
        "Ticks the child again after a SUCCESS, num_cycles times.",
        (PortSpec("num_cycles", IN, int, description="repetitions (-1: forever)"),),
    ),
    decorator(
        Timeout,
        "Halts the child and fails after msec of simulated time.",
        (PortSpec("msec", IN, int, description="time limit in milliseconds"),),
    ),
    decorator(
        Delay,
        "Waits delay_msec of simulated time before ticking the child.",
        (PortSpec("delay_msec", IN, int, description="delay in milliseconds"),),
    ),
    decorator(KeepRunningUntilFailure, "RUNNING after each child SUCCESS; FAILURE when it fails."),
    decorator(
        RunOnce,
        "Ticks the child until it completes once.",
        (PortSpec("then_skip", IN, bool, True, "afterwards SKIPPED (true) or the same status (false)"),),
    ),
    decorator(
        Precondition,
        "Ticks the child only when the script `if` is true.",
        (
            PortSpec("if", IN, str, description="the condition script"),
            PortSpec("else", IN, str, "FAILURE", "status when the condition is false", STATUS_NAMES),
        ),
    ),
    decorator(SkipUnlessUpdated, "Ticks the child only when the entry was written since; else SKIPPED.", (_ENTRY,)),
    decorator(WaitValueUpdate, "Ticks the child only when the entry was written since; else RUNNING.", (_ENTRY,)),
)
