"""BT.CPP 4.10 control nodes, each following the corresponding ``src/controls/*.cpp``: Sequence,
AsyncSequence, SequenceWithMemory, ReactiveSequence, Fallback, AsyncFallback, ReactiveFallback, Parallel,
ParallelAll, IfThenElse, WhileDoElse, TryCatch and Switch2..Switch6."""

from __future__ import annotations

import py_trees

from bt_grasp.tree.builtins.manifest import IN, control
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import NodeKind, NodeSpec, PortSpec
from bt_grasp.tree.values import to_text

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    BtStatus.RUNNING,
    BtStatus.SUCCESS,
    BtStatus.FAILURE,
    BtStatus.SKIPPED,
    BtStatus.IDLE,
)


class Control(BtNode, py_trees.composites.Composite):
    """Base of control nodes; ``halt`` resets every child (halting RUNNING ones) then itself."""

    def __init__(self, ctx: NodeContext) -> None:
        py_trees.composites.Composite.__init__(self, ctx.name, list(ctx.children))
        self._bt_bind(ctx)
        self.ports = ctx.ports
        self.clock = ctx.clock
        self.blackboard = ctx.blackboard  # the tree instance's, as a leaf's (BT.CPP ``config().blackboard``)
        self.kids: list[BtNode] = self.children  # type: ignore[assignment]

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()

    def _tick_child(self, index: int) -> BtStatus:
        status = self.kids[index].execute_tick()
        if status is IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: a child returned IDLE")
        return status


class _Ordered(Control):
    """Sequence and Fallback (BT.CPP ``SequenceNode``/``FallbackNode``), synchronous or async.

    ``_stop_on`` ends the node (FAILURE for a sequence, SUCCESS for a fallback); the other completed
    status moves on to the next child. The async variants give the tick back (RUNNING plus a wake-up)
    after each child that completed within one tick, so a reactive parent re-checks its conditions.
    """

    _stop_on: BtStatus = FAILURE
    _all_done: BtStatus = SUCCESS
    _asynchronous = False

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        if self.bt_state is not RUNNING:
            self.skipped = 0
        self.set_bt_status(RUNNING)
        while self.current < count:
            child = self.kids[self.current]
            before = child.bt_state
            status = self._tick_child(self.current)
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


class Sequence(_Ordered):
    """Ticks children in order; a RUNNING child is resumed next tick, a FAILURE restarts from the first."""


class AsyncSequence(Sequence):
    """Like Sequence, but yields (RUNNING plus a wake-up) after each child that completed synchronously."""

    _asynchronous = True


class Fallback(_Ordered):
    """Ticks children in order until one succeeds; RUNNING is resumed next tick."""

    _stop_on = SUCCESS
    _all_done = FAILURE


class AsyncFallback(Fallback):
    """Like Fallback, but yields (RUNNING plus a wake-up) after each child that failed synchronously."""

    _asynchronous = True


class SequenceWithMemory(Control):
    """Ticks children in order; after a FAILURE the next tick resumes at the failed child (a halt keeps the
    place too). After each child that succeeded synchronously it yields: RUNNING plus a wake-up."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        if self.bt_state is not RUNNING:
            self.skipped = 0
        self.set_bt_status(RUNNING)
        while self.current < count:
            before = self.kids[self.current].bt_state
            status = self._tick_child(self.current)
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

    _stop_on: BtStatus = FAILURE  # the child status that ends the node
    _otherwise: BtStatus = SUCCESS  # the result when every child passed

    def bt_tick(self) -> BtStatus:
        all_skipped = True
        self.set_bt_status(RUNNING)
        for index in range(len(self.kids)):
            status = self._tick_child(index)
            all_skipped = all_skipped and status is SKIPPED
            if status is RUNNING:
                for other in range(len(self.kids)):  # the others go back to IDLE
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


class ReactiveSequence(_Reactive):
    """Re-checks every child each tick; a child failing halts the RUNNING one."""

    _stop_on = FAILURE
    _otherwise = SUCCESS


class ReactiveFallback(_Reactive):
    """Re-checks every child each tick; a child succeeding halts the RUNNING one."""

    _stop_on = SUCCESS
    _otherwise = FAILURE


def _threshold(value: int, count: int) -> int:
    """A Parallel threshold: negative values count from the number of children (-1: all)."""
    return max(count + value + 1, 0) if value < 0 else value


class Parallel(Control):
    """Ticks all unfinished children every tick; ``success_count`` / ``failure_count`` (-1 = all)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.completed: set[int] = set()
        self.success_total = 0
        self.failure_total = 0

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        success_port = int(self.ports.get("success_count"))
        success_threshold = _threshold(success_port, count)
        failure_threshold = _threshold(int(self.ports.get("failure_count")), count)
        if count < success_threshold or count < failure_threshold:
            raise TreeRuntimeError(
                f"{self.bt_path}: {count} children cannot reach success_count={success_threshold} "
                f"or failure_count={failure_threshold}"
            )
        self.set_bt_status(RUNNING)
        skipped = 0
        for index in range(count):
            if index not in self.completed:
                status = self._tick_child(index)
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


class ParallelAll(Control):
    """Ticks all unfinished children until every one completed; FAILURE when at least ``max_failures`` of
    them failed (-1: all), otherwise SUCCESS. A failure does not stop the others."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.completed: set[int] = set()
        self.failure_total = 0

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        failure_threshold = _threshold(int(self.ports.get("max_failures")), count)
        if count < failure_threshold:
            raise TreeRuntimeError(f"{self.bt_path}: {count} children cannot reach max_failures={failure_threshold}")
        self.set_bt_status(RUNNING)
        skipped = 0
        for index in range(count):
            if index in self.completed:
                continue
            status = self._tick_child(index)
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


class IfThenElse(Control):
    """Child 1 is the condition (checked once per activation), child 2 the "then", child 3 the "else"."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.branch = 0

    def bt_tick(self) -> BtStatus:
        self.set_bt_status(RUNNING)
        if self.branch == 0:
            condition = self._tick_child(0)
            if condition is RUNNING:
                return RUNNING
            if condition is SUCCESS:
                self.branch = 1
            elif condition is FAILURE:
                if len(self.kids) == 3:
                    self.branch = 2
                else:
                    return FAILURE
            else:  # a SKIPPED condition chooses no branch (BT.CPP throws a logic error here)
                raise TreeRuntimeError(f"{self.bt_path}: the condition (first child) was skipped")
        status = self._tick_child(self.branch)
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        self.branch = 0
        return status

    def halt(self) -> None:
        self.branch = 0
        super().halt()


class WhileDoElse(Control):
    """Child 1 is re-checked every tick; it switches between child 2 and child 3, halting the other."""

    def bt_tick(self) -> BtStatus:
        self.set_bt_status(RUNNING)
        condition = self._tick_child(0)
        if condition is RUNNING:
            return RUNNING
        status: BtStatus = IDLE
        if condition is SUCCESS:
            if len(self.kids) == 3:
                self.halt_child(2)
            status = self._tick_child(1)
        elif condition is FAILURE:
            if len(self.kids) == 3:
                self.halt_child(1)
                status = self._tick_child(2)
            else:
                status = FAILURE
        if status is RUNNING:
            return RUNNING
        if status is IDLE:  # a skipped condition (BT.CPP returns IDLE to the parent, which then throws)
            raise TreeRuntimeError(f"{self.bt_path}: the condition (first child) was skipped")
        self.reset_children()
        return status


class TryCatch(Control):
    """The children but the last are the "try" block, run as a Sequence; when one fails the last child (the
    "catch") runs to completion and the node FAILS. With ``catch_on_halt`` a halt of the try block also
    runs the catch child once (synchronously: a RUNNING catch is halted)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.skipped = 0
        self.in_catch = False

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        if self.bt_state is not RUNNING:
            self.skipped = 0
            self.in_catch = False
        self.set_bt_status(RUNNING)
        tries = count - 1
        if not self.in_catch:
            while self.current < tries:
                status = self._tick_child(self.current)
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
        status = self._tick_child(count - 1)
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        self.current = 0
        self.in_catch = False
        return FAILURE

    def halt(self) -> None:
        count = len(self.kids)
        if self.ports.get("catch_on_halt") and not self.in_catch and self.bt_state is RUNNING and count >= 2:
            for index in range(count - 1):
                self.halt_child(index)
            if self.kids[-1].execute_tick() is RUNNING:
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

    def bt_tick(self) -> BtStatus:
        match = self.cases
        enums = dict(self._bt_enums)
        if self.ports.has("variable"):
            variable = to_text(self.ports.get("variable"))
            for index in range(self.cases):
                case = f"case_{index + 1}"
                if self.ports.has(case) and switch_matches(variable, to_text(self.ports.get(case)), enums):
                    match = index
                    break
        if self.running_child not in (-1, match):
            self.halt_child(self.running_child)
        status = self._tick_child(match)
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


def _switch_spec(cases: int) -> NodeSpec:
    kind = type(f"Switch{cases}", (Switch,), {"cases": cases, "__doc__": Switch.__doc__})
    cases_ports = [PortSpec(f"case_{k}", IN, str, description=f"the value of case {k}") for k in range(1, cases + 1)]
    ports = (PortSpec("variable", IN, str, description="the value to match"), *cases_ports)
    return NodeSpec(
        f"Switch{cases}",
        NodeKind.CONTROL,
        ports,
        kind,
        f"Ticks the child of the first of {cases} cases equal to variable, else the last (default) child.",
        children=(cases + 1, cases + 1),
    )


SPECS = (
    control(Sequence, "Ticks children in order; resumes a RUNNING child; restarts after a FAILURE."),
    control(AsyncSequence, "Like Sequence, but yields the tick after each child that completed at once."),
    control(SequenceWithMemory, "Like Sequence, but resumes at the failed child next time."),
    control(ReactiveSequence, "Re-evaluates every child each tick; a FAILURE halts the RUNNING one."),
    control(Fallback, "Ticks children in order until one succeeds."),
    control(AsyncFallback, "Like Fallback, but yields the tick after each child that failed at once."),
    control(ReactiveFallback, "Re-evaluates every child each tick; a SUCCESS halts the RUNNING one."),
    control(
        Parallel,
        "Ticks all children; succeeds/fails when enough of them did.",
        (
            PortSpec("success_count", IN, int, -1, "children that must succeed (-1: all)"),
            PortSpec("failure_count", IN, int, 1, "children that must fail (-1: all)"),
        ),
    ),
    control(
        ParallelAll,
        "Ticks all children until every one completed; FAILURE when max_failures of them failed.",
        (PortSpec("max_failures", IN, int, 1, "failures that make the node fail (-1: all)"),),
    ),
    control(IfThenElse, "If child 1 succeeds tick child 2, else child 3 (or FAILURE).", children=(2, 3)),
    control(WhileDoElse, "Re-checks child 1 every tick; runs child 2 or child 3.", children=(2, 3)),
    control(
        TryCatch,
        "Runs the children but the last as a Sequence; on a failure runs the last (catch) child and fails.",
        (PortSpec("catch_on_halt", IN, bool, False, "also run the catch child when halted during the try block"),),
        children=(2, None),
    ),
    *(_switch_spec(cases) for cases in range(2, 7)),
)
