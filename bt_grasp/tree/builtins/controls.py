"""BT.CPP v4 control nodes: Sequence, SequenceWithMemory, ReactiveSequence, Fallback, ReactiveFallback,
Parallel, IfThenElse, WhileDoElse. Each follows the corresponding ``src/controls/*.cpp`` of BT.CPP 4.x."""

from __future__ import annotations

import py_trees

from bt_grasp.tree.builtins.manifest import IN, control
from bt_grasp.tree.context import NodeContext
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.node import BtNode, BtStatus
from bt_grasp.tree.registry import PortSpec

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
        self.kids: list[BtNode] = self.children  # type: ignore[assignment]

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()

    def _tick_child(self, index: int) -> BtStatus:
        status = self.kids[index].execute_tick()
        if status is IDLE:
            raise TreeRuntimeError(f"{self.bt_path}: a child returned IDLE")
        return status


class Sequence(Control):
    """Ticks children in order; a RUNNING child is resumed next tick, a FAILURE restarts from the first."""

    _reset_on_failure = True

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
            status = self._tick_child(self.current)
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                if self._reset_on_failure:
                    self.reset_children()
                    self.current = 0
                else:  # SequenceWithMemory keeps its place: only the rest is halted
                    self.halt_children(self.current)
                return FAILURE
            if status is SKIPPED:
                self.skipped += 1
            self.current += 1
        all_skipped = self.skipped == count
        self.reset_children()
        self.current = 0
        self.skipped = 0
        return SKIPPED if all_skipped else SUCCESS

    def halt(self) -> None:
        if self._reset_on_failure:
            self.current = 0
        self.skipped = 0
        super().halt()


class SequenceWithMemory(Sequence):
    """Like Sequence, but after a FAILURE the next tick resumes at the child that failed."""

    _reset_on_failure = False


class Fallback(Control):
    """Ticks children in order until one succeeds; RUNNING is resumed next tick."""

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
            status = self._tick_child(self.current)
            if status is RUNNING:
                return RUNNING
            if status is SUCCESS:
                self.reset_children()
                self.current = 0
                return SUCCESS
            if status is SKIPPED:
                self.skipped += 1
            self.current += 1
        all_skipped = self.skipped == count
        self.reset_children()
        self.current = 0
        self.skipped = 0
        return SKIPPED if all_skipped else FAILURE

    def halt(self) -> None:
        self.current = 0
        self.skipped = 0
        super().halt()


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


class Parallel(Control):
    """Ticks all unfinished children every tick; ``success_count`` / ``failure_count`` (-1 = all)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.completed: set[int] = set()
        self.success_total = 0
        self.failure_total = 0

    def _threshold(self, port: str) -> int:
        value = int(self.ports.get(port))
        return max(len(self.kids) + value + 1, 0) if value < 0 else value

    def bt_tick(self) -> BtStatus:
        count = len(self.kids)
        success_threshold = self._threshold("success_count")
        failure_threshold = self._threshold("failure_count")
        if count < success_threshold or count < failure_threshold:
            raise TreeRuntimeError(
                f"{self.bt_path}: {count} children cannot reach success_count={success_threshold} "
                f"or failure_count={failure_threshold}"
            )
        self.set_bt_status(RUNNING)
        skipped = 0
        success_is_all = int(self.ports.get("success_count")) < 0
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
                success_is_all and self.success_total + skipped >= success_threshold
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
            else:  # SKIPPED condition: BT.CPP leaves the node as it is
                return SKIPPED
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
        else:
            return SKIPPED
        if status is RUNNING:
            return RUNNING
        self.reset_children()
        return status


SPECS = (
    control(Sequence, "Ticks children in order; resumes a RUNNING child; restarts after a FAILURE."),
    control(SequenceWithMemory, "Like Sequence, but resumes at the failed child next time."),
    control(ReactiveSequence, "Re-evaluates every child each tick; a FAILURE halts the RUNNING one."),
    control(Fallback, "Ticks children in order until one succeeds."),
    control(ReactiveFallback, "Re-evaluates every child each tick; a SUCCESS halts the RUNNING one."),
    control(
        Parallel,
        "Ticks all children; succeeds/fails when enough of them did.",
        (
            PortSpec("success_count", IN, int, -1, "children that must succeed (-1: all)"),
            PortSpec("failure_count", IN, int, 1, "children that must fail (-1: all)"),
        ),
    ),
    control(IfThenElse, "If child 1 succeeds tick child 2, else child 3 (or FAILURE).", children=(2, 3)),
    control(WhileDoElse, "Re-checks child 1 every tick; runs child 2 or child 3.", children=(2, 3)),
)
