"""BT.CPP 4.10 control nodes, each following the corresponding ``src/controls/*.cpp``: Sequence,
AsyncSequence, SequenceWithMemory, ReactiveSequence, Fallback, AsyncFallback, ReactiveFallback, Parallel,
ParallelAll, IfThenElse, WhileDoElse, TryCatch and Switch2..Switch6.

They are written as a plugin's controls are (``docs/own-leaves.md``): declared with ``@control``, ticking and
halting their children with ``tick_child``, ``halt_child`` and ``reset_children``, registered by
:func:`register`."""

from __future__ import annotations

from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node_api import Control, NodeContext, NodeRegistry, Status, control, input_port
from bt_grasp.tree.registry import PortSpec

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    Status.RUNNING,
    Status.SUCCESS,
    Status.FAILURE,
    Status.SKIPPED,
    Status.IDLE,
)


class _Ordered(Control):
    """Sequence and Fallback (BT.CPP ``SequenceNode``/``FallbackNode``), synchronous or async.

    ``_stop_on`` ends the node (FAILURE for a sequence, SUCCESS for a fallback); the other completed
    status moves on to the next child. The async variants give the tick back (RUNNING plus a wake-up)
    after each child that completed within one tick, so a reactive parent re-checks its conditions.
    """

    _stop_on: Status = FAILURE
    _all_done: Status = SUCCESS
    _asynchronous = False

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        if self.bt_state is not RUNNING:
            self.skipped = 0
        self.set_bt_status(RUNNING)
        while self.current < count:
            child = self.child_nodes[self.current]
            before = child.bt_state
            status = self.tick_child(self.current)
            if status is RUNNING:
                return RUNNING
            if status is self._stop_on:
                self.reset_children()
                self.current = 0
                return status
            self.current += 1
            if status is SKIPPED:
                self.skipped += 1
            elif self._asynchronous and before is IDLE and self.current < count:
                self.emit_wake_up()
                return RUNNING
        all_skipped = self.skipped == count
        self.reset_children()
        self.current = 0
        self.skipped = 0
        return SKIPPED if all_skipped else self._all_done

    def halt(self) -> None:
        self.current = 0
        self.skipped = 0
        super().halt()


@control(description="Ticks children in order; resumes a RUNNING child; restarts after a FAILURE.")
class Sequence(_Ordered):
    """Ticks children in order; a RUNNING child is resumed next tick, a FAILURE restarts from the first."""


@control(description="Like Sequence, but yields the tick after each child that completed at once.")
class AsyncSequence(Sequence):
    """Like Sequence, but yields (RUNNING plus a wake-up) after each child that completed synchronously."""

    _asynchronous = True


@control(description="Ticks children in order until one succeeds.")
class Fallback(_Ordered):
    """Ticks children in order until one succeeds; RUNNING is resumed next tick."""

    _stop_on = SUCCESS
    _all_done = FAILURE


@control(description="Like Fallback, but yields the tick after each child that failed at once.")
class AsyncFallback(Fallback):
    """Like Fallback, but yields (RUNNING plus a wake-up) after each child that failed synchronously."""

    _asynchronous = True


@control(description="Like Sequence, but resumes at the failed child next time.")
class SequenceWithMemory(Control):
    """Ticks children in order; after a FAILURE the next tick resumes at the failed child (a halt keeps the
    place too). After each child that succeeded synchronously it yields: RUNNING plus a wake-up."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        if self.bt_state is not RUNNING:
            self.skipped = 0
        self.set_bt_status(RUNNING)
        while self.current < count:
            before = self.child_nodes[self.current].bt_state
            status = self.tick_child(self.current)
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                self.halt_children(self.current)
                return FAILURE
            self.current += 1
            if status is SKIPPED:
                self.skipped += 1
            elif before is IDLE and self.current < count:
                self.emit_wake_up()
                return RUNNING
        all_skipped = self.skipped == count
        self.reset_children()
        self.current = 0
        self.skipped = 0
        return SKIPPED if all_skipped else SUCCESS


class _Reactive(Control):
    """ReactiveSequence / ReactiveFallback: every tick starts again from the first child."""

    _stop_on: Status = FAILURE  # the child status that ends the node
    _otherwise: Status = SUCCESS  # the result when every child passed

    def bt_tick(self) -> Status:
        all_skipped = True
        self.set_bt_status(RUNNING)
        for index in range(len(self.child_nodes)):
            status = self.tick_child(index)
            all_skipped = all_skipped and status is SKIPPED
            if status is RUNNING:
                for other in range(len(self.child_nodes)):  # the others go back to IDLE
                    if other != index:
                        self.halt_child(other)
                return RUNNING
            if status is self._stop_on:
                self.reset_children()
                return status
            if status is SKIPPED:
                self.halt_child(index)
        self.reset_children()
        return SKIPPED if all_skipped else self._otherwise


@control(description="Re-evaluates every child each tick; a FAILURE halts the RUNNING one.")
class ReactiveSequence(_Reactive):
    """Re-checks every child each tick; a child failing halts the RUNNING one."""

    _stop_on = FAILURE
    _otherwise = SUCCESS


@control(description="Re-evaluates every child each tick; a SUCCESS halts the RUNNING one.")
class ReactiveFallback(_Reactive):
    """Re-checks every child each tick; a child succeeding halts the RUNNING one."""

    _stop_on = SUCCESS
    _otherwise = FAILURE


def _threshold(value: int, count: int) -> int:
    """A Parallel threshold: negative values count from the number of children (-1: all)."""
    return max(count + value + 1, 0) if value < 0 else value


@control(
    ports=[
        input_port("success_count", int, -1, "children that must succeed (-1: all)"),
        input_port("failure_count", int, 1, "children that must fail (-1: all)"),
    ],
    description="Ticks all children; succeeds/fails when enough of them did.",
)
class Parallel(Control):
    """Ticks all unfinished children every tick; ``success_count`` / ``failure_count`` (-1 = all)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.completed: set[int] = set()
        self.success_total = 0
        self.failure_total = 0

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        success_port = self.ports.require("success_count", int)
        success_threshold = _threshold(success_port, count)
        failure_threshold = _threshold(self.ports.require("failure_count", int), count)
        if count < success_threshold or count < failure_threshold:
            raise TreeRuntimeError(
                f"{self.bt_path}: {count} children cannot reach success_count={success_threshold} "
                f"or failure_count={failure_threshold}"
            )
        self.set_bt_status(RUNNING)
        skipped = 0
        for index in range(count):
            if index not in self.completed:
                status = self.tick_child(index)
                if status is SKIPPED:
                    skipped += 1
                elif status is SUCCESS:
                    self.completed.add(index)
                    self.success_total += 1
                elif status is FAILURE:
                    self.completed.add(index)
                    self.failure_total += 1
            if self.success_total >= success_threshold or (
                success_port < 0 and self.success_total + skipped >= success_threshold
            ):
                self._clear()
                self.reset_children()
                return SUCCESS
            if count - self.failure_total < success_threshold or self.failure_total == failure_threshold:
                self._clear()
                self.reset_children()
                return FAILURE
        return SKIPPED if skipped == count else RUNNING

    def _clear(self) -> None:
        self.completed.clear()
        self.success_total = 0
        self.failure_total = 0

    def halt(self) -> None:
        self._clear()
        super().halt()


@control(
    ports=[input_port("max_failures", int, 1, "failures that make the node fail (-1: all)")],
    description="Ticks all children until every one completed; FAILURE when max_failures of them failed.",
)
class ParallelAll(Control):
    """Ticks all unfinished children until every one completed; FAILURE when at least ``max_failures`` of
    them failed (-1: all), otherwise SUCCESS. A failure does not stop the others."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.completed: set[int] = set()
        self.failure_total = 0

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        failure_threshold = _threshold(self.ports.require("max_failures", int), count)
        if count < failure_threshold:
            raise TreeRuntimeError(f"{self.bt_path}: {count} children cannot reach max_failures={failure_threshold}")
        self.set_bt_status(RUNNING)
        skipped = 0
        for index in range(count):
            if index in self.completed:
                continue
            status = self.tick_child(index)
            if status is SUCCESS:
                self.completed.add(index)
            elif status is FAILURE:
                self.completed.add(index)
                self.failure_total += 1
            elif status is SKIPPED:
                skipped += 1
        if skipped == count:
            return SKIPPED
        if skipped + len(self.completed) >= count:
            self.halt_children()
            self.completed.clear()
            result = FAILURE if self.failure_total >= failure_threshold else SUCCESS
            self.failure_total = 0
            return result
        return RUNNING

    def halt(self) -> None:
        self.completed.clear()
        self.failure_total = 0
        super().halt()


@control(description="If child 1 succeeds tick child 2, else child 3 (or FAILURE).", children=(2, 3))
class IfThenElse(Control):
    """Child 1 is the condition (checked once per activation), child 2 the "then", child 3 the "else"."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.branch = 0

    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        if self.branch == 0:
            condition = self.tick_child(0)
            if condition is RUNNING:
                return RUNNING
            if condition is SUCCESS:
                self.branch = 1
            elif condition is FAILURE:
                if len(self.child_nodes) == 3:
                    self.branch = 2
                else:
                    return FAILURE
            else:  # a SKIPPED condition chooses no branch (BT.CPP throws a logic error here)
                raise TreeRuntimeError(f"{self.bt_path}: the condition (first child) was skipped")
        status = self.tick_child(self.branch)
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        self.branch = 0
        return status

    def halt(self) -> None:
        self.branch = 0
        super().halt()


@control(description="Re-checks child 1 every tick; runs child 2 or child 3.", children=(2, 3))
class WhileDoElse(Control):
    """Child 1 is re-checked every tick; it switches between child 2 and child 3, halting the other."""

    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        condition = self.tick_child(0)
        if condition is RUNNING:
            return RUNNING
        status: Status = IDLE
        if condition is SUCCESS:
            if len(self.child_nodes) == 3:
                self.halt_child(2)
            status = self.tick_child(1)
        elif condition is FAILURE:
            if len(self.child_nodes) == 3:
                self.halt_child(1)
                status = self.tick_child(2)
            else:
                status = FAILURE
        if status is RUNNING:
            return RUNNING
        if status is IDLE:  # a skipped condition (BT.CPP returns IDLE to the parent, which then throws)
            raise TreeRuntimeError(f"{self.bt_path}: the condition (first child) was skipped")
        self.reset_children()
        return status


@control(
    ports=[input_port("catch_on_halt", bool, False, "also run the catch child when halted during the try block")],
    description="Runs the children but the last as a Sequence; on a failure runs the last (catch) child and fails.",
    children=(2, None),
)
class TryCatch(Control):
    """The children but the last are the "try" block, run as a Sequence; when one fails the last child (the
    "catch") runs to completion and the node FAILS. With ``catch_on_halt`` a halt of the try block also
    runs the catch child once (synchronously: a RUNNING catch is halted)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0
        self.in_catch = False

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        if self.bt_state is not RUNNING:
            self.skipped = 0
            self.in_catch = False
        self.set_bt_status(RUNNING)
        tries = count - 1
        if not self.in_catch:
            while self.current < tries:
                status = self.tick_child(self.current)
                if status is RUNNING:
                    return RUNNING
                if status is FAILURE:
                    self.reset_children()
                    self.current = 0
                    self.in_catch = True
                    break
                self.current += 1
                if status is SKIPPED:
                    self.skipped += 1
            else:
                all_skipped = self.skipped == tries
                self.reset_children()
                self.current = 0
                self.skipped = 0
                return SKIPPED if all_skipped else SUCCESS
        status = self.tick_child(count - 1)
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        self.current = 0
        self.in_catch = False
        return FAILURE

    def halt(self) -> None:
        count = len(self.child_nodes)
        if self.ports.get("catch_on_halt", bool) and not self.in_catch and self.bt_state is RUNNING and count >= 2:
            for index in range(count - 1):
                self.halt_child(index)
            if self.child_nodes[-1].execute_tick() is RUNNING:
                self.halt_child(count - 1)
        self.current = 0
        self.skipped = 0
        self.in_catch = False
        super().halt()


def _as_int(text: str, enums: dict[str, int]) -> int | None:
    if text in enums:
        return enums[text]
    try:
        return int(text) if text.strip() == text and text.lstrip("-").isdigit() else None
    except ValueError:
        return None


def _as_real(text: str, enums: dict[str, int]) -> float | None:
    if text in enums:
        return float(enums[text])
    if not text or text[0] in " \t+" or "_" in text:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def switch_matches(variable: str, case: str, enums: dict[str, int]) -> bool:
    """BT.CPP ``CheckStringEquality``: equal texts, else equal integers, else reals within float epsilon
    (enum names count as their values)."""
    if variable == case:
        return True
    left, right = _as_int(variable, enums), _as_int(case, enums)
    if left is not None and right is not None and left == right:
        return True
    real_left, real_right = _as_real(variable, enums), _as_real(case, enums)
    return real_left is not None and real_right is not None and abs(real_left - real_right) <= 1.1920928955078125e-07


class Switch(Control):
    """``SwitchN``: ticks the child whose ``case_K`` matches ``variable`` (compared as text, then as numbers),
    else the last child; a RUNNING child that no longer matches is halted."""

    cases = 0

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.running_child = -1

    def bt_tick(self) -> Status:
        match = self.cases
        enums = dict(self.enums)
        variable = self.ports.get("variable", str)
        if variable is not None:  # no variable: the default child, as BT.CPP
            for index in range(self.cases):
                case = self.ports.get(f"case_{index + 1}", str)
                if case is not None and switch_matches(variable, case, enums):
                    match = index
                    break
        if self.running_child not in (-1, match):
            self.halt_child(self.running_child)
        status = self.tick_child(match)
        if status is SKIPPED:
            self.running_child = -1
        elif status is RUNNING:
            self.running_child = match
        else:
            self.reset_children()
            self.running_child = -1
        return status

    def halt(self) -> None:
        self.running_child = -1
        super().halt()


def _switch_ports(cases: int) -> list[PortSpec]:
    return [input_port("variable", str, description="the value to match"),
            *(input_port(f"case_{k}", str, description=f"the value of case {k}") for k in range(1, cases + 1))]


def _switch(cases: int) -> str:
    return f"Ticks the child of the first of {cases} cases equal to variable, else the last (default) child."


@control(ports=_switch_ports(2), description=_switch(2), children=(3, 3))
class Switch2(Switch):
    cases = 2


@control(ports=_switch_ports(3), description=_switch(3), children=(4, 4))
class Switch3(Switch):
    cases = 3


@control(ports=_switch_ports(4), description=_switch(4), children=(5, 5))
class Switch4(Switch):
    cases = 4


@control(ports=_switch_ports(5), description=_switch(5), children=(6, 6))
class Switch5(Switch):
    cases = 5


@control(ports=_switch_ports(6), description=_switch(6), children=(7, 7))
class Switch6(Switch):
    cases = 6


NODES: tuple[type[Control], ...] = (
    Sequence, AsyncSequence, SequenceWithMemory, ReactiveSequence, Fallback, AsyncFallback, ReactiveFallback, Parallel,
    ParallelAll, IfThenElse, WhileDoElse, TryCatch, Switch2, Switch3, Switch4, Switch5, Switch6,
)


def register(registry: NodeRegistry) -> None:
    """BT.CPP's built-in controls, registered as a plugin registers its nodes."""
    for node in NODES:
        registry.register(node)
