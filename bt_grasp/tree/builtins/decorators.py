"""BT.CPP 4.10 decorators, each following the corresponding ``src/decorators/*``: Inverter, ForceSuccess,
ForceFailure, RetryUntilSuccessful, Repeat, Timeout, Delay, KeepRunningUntilFailure, RunOnce, Precondition,
SkipUnlessUpdated and WaitValueUpdate (the Loop* family is in :mod:`bt_grasp.tree.builtins.loops`).
Timeout and Delay read the injected simulated clock, never the wall clock.

They are written as a plugin's decorators are (``docs/own-leaves.md``): declared with ``@decorator``, ticking
and halting the child with ``tick_child`` and ``halt_child``, registered by :func:`register`."""

from __future__ import annotations

from bt_grasp.tree.exceptions import ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.node_api import Decorator, NodeContext, NodeRegistry, Status, decorator, input_port
from bt_grasp.tree.ports import EntryWatch
from bt_grasp.tree.registry import PortSpec
from bt_grasp.tree.scripting import Program, parse_script

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    Status.RUNNING,
    Status.SUCCESS,
    Status.FAILURE,
    Status.SKIPPED,
    Status.IDLE,
)
#: the literal statuses a port such as Precondition's ``else`` accepts
STATUS_NAMES = ("SUCCESS", "FAILURE", "SKIPPED", "RUNNING")


@decorator(description="Swaps SUCCESS and FAILURE.")
class Inverter(Decorator):
    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            return FAILURE if status is SUCCESS else SUCCESS
        return status


@decorator(description="SUCCESS whenever the child completes.")
class ForceSuccess(Decorator):
    _forced = SUCCESS

    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
            return self._forced
        return status


@decorator(description="FAILURE whenever the child completes.")
class ForceFailure(ForceSuccess):
    _forced = FAILURE


@decorator(description="RUNNING after each child SUCCESS; FAILURE when it fails.")
class KeepRunningUntilFailure(Decorator):
    """RUNNING after each child success (the child starts again next tick); FAILURE when the child fails."""

    def bt_tick(self) -> Status:
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
    _again: Status = FAILURE  # the status that makes the loop go round

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.count = 0

    def bt_tick(self) -> Status:
        limit = self.ports.require(self._port, int)
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
            limit = self.ports.require(self._port, int)
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


@decorator(
    ports=[input_port("num_attempts", int, description="attempts before failing (-1: forever)", required=True)],
    description="Ticks the child again after a FAILURE, up to num_attempts times.",
)
class RetryUntilSuccessful(_Loop):
    """Ticks the child again after each FAILURE, up to ``num_attempts`` attempts (-1: forever)."""

    _port = "num_attempts"
    _again = FAILURE


@decorator(
    ports=[input_port("num_cycles", int, description="repetitions (-1: forever)", required=True)],
    description="Ticks the child again after a SUCCESS, num_cycles times.",
)
class Repeat(_Loop):
    """Ticks the child again after each SUCCESS, ``num_cycles`` times (-1: forever)."""

    _port = "num_cycles"
    _again = SUCCESS


@decorator(
    ports=[input_port("msec", int, description="time limit in milliseconds", required=True)],
    description="Halts the child and fails after msec of simulated time.",
)
class Timeout(Decorator):
    """Halts the RUNNING child and fails once ``msec`` of simulated time passed since it started
    (``msec`` 0: no limit). The time is checked when the node is ticked, once per control period."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.started = False
        self.start_ns = 0

    def bt_tick(self) -> Status:
        msec = self.ports.require("msec", int)
        now = self.clock.now_ns()
        if not self.started:
            self.started = True
            self.start_ns = now
            self.set_bt_status(RUNNING)
        elif msec > 0 and now - self.start_ns >= msec * 1_000_000 and self.child.bt_state is RUNNING:
            self.feedback_message = f"timed out after {msec} ms"
            self.halt_child()
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


@decorator(
    ports=[input_port("delay_msec", int, description="delay in milliseconds", required=True)],
    description="Waits delay_msec of simulated time before ticking the child.",
)
class Delay(Decorator):
    """RUNNING until ``delay_msec`` of simulated time passed, then ticks the child."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.started = False
        self.start_ns = 0

    def bt_tick(self) -> Status:
        delay_ns = self.ports.require("delay_msec", int) * 1_000_000
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


@decorator(
    ports=[input_port("then_skip", bool, True, "afterwards SKIPPED (true) or the same status (false)")],
    description="Ticks the child until it completes once.",
)
class RunOnce(Decorator):
    """Ticks the child until it completes once; afterwards SKIPPED (``then_skip``) or that same status.
    The memory survives halts and resets, as in BT.CPP."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.done: Status | None = None

    def bt_tick(self) -> Status:
        if self.done is not None:
            return SKIPPED if self.ports.require("then_skip", bool) else self.done
        self.set_bt_status(RUNNING)
        status = self.tick_child()
        if status.completed:
            self.done = status
            self.reset_child()
        return status


@decorator(
    ports=[
        input_port("if", str, description="the condition script", required=True),
        input_port("else", str, "FAILURE", "status when the condition is false", choices=STATUS_NAMES),
    ],
    description="Ticks the child only when the script `if` is true.",
)
class Precondition(Decorator):
    """Ticks the child when the ``if`` script is true (checked when the child is not running yet);
    otherwise returns ``else`` (FAILURE by default)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.child_running = False
        self._program: Program | None = None
        if ctx.ports.key("if") is None:
            self._program = parse_script(ctx.ports.require("if", str))

    def _script(self) -> Program:
        if self._program is not None:
            return self._program
        try:
            return parse_script(self.ports.require("if", str))
        except ScriptSyntaxError as exc:
            raise TreeRuntimeError(f"{self.bt_path}: {exc}") from None

    def bt_tick(self) -> Status:
        otherwise = Status(self.ports.require("else", str))
        if not self.child_running:
            self.child_running = self._script().truth(self.blackboard, self.enums)
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


def _entry_port() -> PortSpec:
    return input_port("entry", object, description="the blackboard entry to watch ({key} or key)", required=True)


class _EntryUpdated(Decorator):
    """SkipUnlessUpdated / WaitValueUpdate (BT.CPP ``EntryUpdatedDecorator``): the child is ticked only when
    the entry was written since this node last looked (a RUNNING child is resumed regardless)."""

    _not_updated: Status = SKIPPED

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.watch = EntryWatch(ctx.attributes.get("entry", ""))
        self.child_running = False

    def bt_tick(self) -> Status:
        if not self.child_running and not self.watch.written_since(self.blackboard):
            return self._not_updated
        status = self.tick_child()
        self.child_running = status is RUNNING
        return status

    def halt(self) -> None:
        self.child_running = False
        super().halt()


@decorator(
    ports=[_entry_port()], description="Ticks the child only when the entry was written since; else SKIPPED.",
)
class SkipUnlessUpdated(_EntryUpdated):
    _not_updated = SKIPPED


@decorator(
    ports=[_entry_port()], description="Ticks the child only when the entry was written since; else RUNNING.",
)
class WaitValueUpdate(_EntryUpdated):
    _not_updated = RUNNING


NODES: tuple[type[Decorator], ...] = (
    Inverter, ForceSuccess, ForceFailure, RetryUntilSuccessful, Repeat, Timeout, Delay, KeepRunningUntilFailure,
    RunOnce, Precondition, SkipUnlessUpdated, WaitValueUpdate,
)


def register(registry: NodeRegistry) -> None:
    """BT.CPP's built-in decorators, registered as a plugin registers its nodes."""
    for node in NODES:
        registry.register(node)
