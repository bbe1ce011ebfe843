"""A user's own nodes, written only against the public API (bt_grasp.nodes), as docs/own-leaves.md shows.

- CheckWeight: a condition with a user failure reason (WEIGHT_OUT_OF_RANGE);
- WaitSim: an action that waits in simulated time (RUNNING until its deadline);
- RoundRobinFallback: a control node; each activation starts at the child after the one that last succeeded;
- RateLimit: a decorator; it ticks its child at most once per ``period_msec`` of simulated time.
"""

from __future__ import annotations

from bt_grasp.nodes import (
    Control,
    Deadline,
    Decorator,
    Leaf,
    NodeContext,
    NodeRegistry,
    Reason,
    Status,
    action,
    condition,
    control,
    decorator,
    input_port,
)

WEIGHT_OUT_OF_RANGE = Reason("WEIGHT_OUT_OF_RANGE", "The weighed object is heavier than allowed.")


@condition(ports=[input_port("grams", float, description="the measured weight"),
                  input_port("max_grams", float, 500.0, "the heaviest allowed")])
class CheckWeight(Leaf):
    """SUCCESS when the weight is at most max_grams."""

    def update(self) -> Status:
        grams, limit = self.ports.require("grams", float), self.ports.require("max_grams", float)
        if grams > limit:
            return self.fail(WEIGHT_OUT_OF_RANGE, f"{grams:g} g is more than {limit:g} g")
        return Status.SUCCESS


@action(ports=[input_port("seconds", float, 0.05, "how long to wait, in simulated seconds")])
class WaitSim(Leaf):
    """RUNNING until the given simulated time has passed, then SUCCESS."""

    def initialise(self) -> None:
        self.deadline = Deadline.after(self.clock, self.ports.require("seconds", float))

    def update(self) -> Status:
        return Status.SUCCESS if self.deadline.passed() else Status.RUNNING


@control()
class RoundRobinFallback(Control):
    """A Fallback whose activations start at the child after the one that last succeeded."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.start = 0  # where the next activation begins
        self.current = 0  # the child being tried (resumed when it was RUNNING)
        self.tried = 0  # how many children this activation has tried

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        if self.bt_state is not Status.RUNNING:
            self.current, self.tried = self.start, 0
        self.set_bt_status(Status.RUNNING)
        while self.tried < count:
            status = self.tick_child(self.current)
            if status is Status.RUNNING:
                return Status.RUNNING
            if status is Status.SUCCESS:
                self.start = (self.current + 1) % count
                self.reset_children()
                return Status.SUCCESS
            self.current = (self.current + 1) % count
            self.tried += 1
        self.reset_children()
        return Status.FAILURE

    def halt(self) -> None:
        self.tried = 0
        super().halt()


@decorator(ports=[input_port("period_msec", int, description="least simulated time between two child runs")])
class RateLimit(Decorator):
    """Ticks the child at most once per period of simulated time; FAILURE (not ticking it) in between."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.last_start_ns: int | None = None

    def bt_tick(self) -> Status:
        now = self.clock.now_ns()
        period_ns = self.ports.require("period_msec", int) * 1_000_000
        if self.child.bt_state is not Status.RUNNING:
            if self.last_start_ns is not None and now - self.last_start_ns < period_ns:
                self.feedback_message = "rate limited"
                return Status.FAILURE
            self.last_start_ns = now
        self.set_bt_status(Status.RUNNING)
        status = self.tick_child()
        if status.completed:
            self.reset_child()
        return status


def register(registry: NodeRegistry) -> None:
    registry.register_reason(WEIGHT_OUT_OF_RANGE)
    for cls in (CheckWeight, WaitSim, RoundRobinFallback, RateLimit):
        registry.register(cls)
