"""BT.CPP v4 decorators: Inverter, ForceSuccess, ForceFailure, RetryUntilSuccessful, Repeat, Timeout, Delay,
KeepRunningUntilFailure, RunOnce, Precondition. Timeout and Delay read the injected
simulated clock, never the wall clock."""

from __future__ import annotations

import py_trees

from bt_grasp.tree.builtins.manifest import IN, STATUS_NAMES, decorator
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import PortSpec
from bt_grasp.tree.scripting import Program, parse_script

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    BtStatus.RUNNING,
    BtStatus.SUCCESS,
    BtStatus.FAILURE,
    BtStatus.SKIPPED,
    BtStatus.IDLE,
)

#: a RetryUntilSuccessful/Repeat with -1 gives the tick back after this many synchronous rounds
SYNC_LOOP_LIMIT = 10_000


class Decorator(BtNode, py_trees.decorators.Decorator):
    """Base of decorators; ``halt`` resets the child (halting it when RUNNING) then itself."""

    def __init__(self, ctx: NodeContext) -> None:
        (child,) = ctx.children
        py_trees.decorators.Decorator.__init__(self, ctx.name, child)
        self._bt_bind(ctx)
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.child: BtNode = child  # type: ignore[assignment]

    def update(self) -> py_trees.common.Status:  # pragma: no cover - py_trees never calls it here
        return self.status

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
        if status is SUCCESS:
            self.reset_child()
            return RUNNING
        if status is FAILURE:
            self.reset_child()
            return FAILURE
        return status


class RetryUntilSuccessful(Decorator):
    """Ticks the child again after each FAILURE, within the same tick, up to ``num_attempts`` (-1: forever)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.tries = 0

    def bt_tick(self) -> BtStatus:
        attempts = int(self.ports.get("num_attempts"))
        self.set_bt_status(RUNNING)
        rounds = 0
        while self.tries < attempts or attempts == -1:
            status = self.tick_child()
            if status is SUCCESS:
                self.tries = 0
                self.reset_child()
                return SUCCESS
            if status is RUNNING:
                return RUNNING
            if status is SKIPPED:
                self.reset_child()
                return SKIPPED
            self.tries += 1
            attempts = int(self.ports.get("num_attempts"))
            self.reset_child()
            rounds += 1
            if attempts == -1 and rounds >= SYNC_LOOP_LIMIT:
                return RUNNING
        self.tries = 0
        return FAILURE

    def halt(self) -> None:
        self.tries = 0
        super().halt()


class Repeat(Decorator):
    """Ticks the child again after each SUCCESS, within the same tick, ``num_cycles`` times (-1: forever)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.count = 0

    def bt_tick(self) -> BtStatus:
        cycles = int(self.ports.get("num_cycles"))
        self.set_bt_status(RUNNING)
        rounds = 0
        while self.count < cycles or cycles == -1:
            status = self.tick_child()
            if status is SUCCESS:
                self.count += 1
                self.reset_child()
                rounds += 1
                if cycles == -1 and rounds >= SYNC_LOOP_LIMIT:
                    return RUNNING
                continue
            if status is FAILURE:
                self.count = 0
                self.reset_child()
                return FAILURE
            if status is RUNNING:
                return RUNNING
            self.reset_child()  # SKIPPED
            return SKIPPED
        self.count = 0
        return SUCCESS

    def halt(self) -> None:
        self.count = 0
        super().halt()


class Timeout(Decorator):
    """Halts the RUNNING child and fails once ``msec`` of simulated time passed since it started."""

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
    """Ticks the child until it completes once; afterwards SKIPPED (``then_skip``) or that same status."""

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
)
