"""Nav2's RecoveryNode, PipelineSequence, RoundRobin and RateController, line for line from Nav2's
nav2_behavior_tree/plugins (commit a3a97043ee93d92fe8d70ec56d183933169beb1c, Apache-2.0; see NOTICE), written with
bt_grasp's node API: the controls and decorators navigate_to_pose_w_replanning_and_recovery.xml needs, as in
BT.CPP they come from Nav2's library. Its leaves need no Python: a dry run stands in for them from
nav2_tree_nodes.xml. The C++ twin the differential driver registers is tools/btcpp_diff/nav2_controls.hpp; keep the
two equal. RateController counts simulated time (Nav2's reads the wall clock).
"""

from __future__ import annotations

from bt_grasp.nodes import (
    Control,
    Decorator,
    NodeContext,
    NodeRegistry,
    Status,
    control,
    decorator,
    input_port,
)

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.SKIPPED, Status.IDLE


@control(ports=[input_port("number_of_retries", int, 1, "Number of retries")], children=(2, 2))
class RecoveryNode(Control):
    """Ticks the second child when the first fails, then the first again, at most number_of_retries times."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current_child_idx = 0
        self.retry_count = 0

    def bt_tick(self) -> Status:
        retries = self.ports.require("number_of_retries", int)
        self.set_bt_status(RUNNING)
        while self.current_child_idx < 2 and self.retry_count <= retries:
            status = self.tick_child(self.current_child_idx)
            if self.current_child_idx == 0:
                if status is SKIPPED:
                    self.halt()
                    return SKIPPED
                if status is SUCCESS:
                    self.halt_child(1)
                    self.halt()
                    return SUCCESS
                if status is RUNNING:
                    return RUNNING
                if self.retry_count < retries:
                    self.halt_child(0)
                    self.current_child_idx += 1
                    continue
                self.halt()
                return FAILURE
            if status is SKIPPED:
                self.current_child_idx = 0
                self.halt_child(1)
                return FAILURE
            if status is RUNNING:
                return RUNNING
            if status is SUCCESS:
                self.halt_child(1)
                self.retry_count += 1
                self.current_child_idx = 0
                continue
            self.halt()
            return FAILURE
        self.halt()
        return FAILURE

    def halt(self) -> None:
        super().halt()
        self.retry_count = 0
        self.current_child_idx = 0


@control()
class PipelineSequence(Control):
    """Ticks every child from the first each tick; a child before the RUNNING one may be RUNNING too."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.last_child_ticked = 0

    def bt_tick(self) -> Status:
        skipped = 0
        for index in range(len(self.child_nodes)):
            status = self.tick_child(index)
            if status is FAILURE:
                self.halt_children()
                self.last_child_ticked = 0
                return status
            if status is SKIPPED:
                skipped += 1
            elif status is RUNNING and index >= self.last_child_ticked:
                self.last_child_ticked = index
                return status
        self.halt_children()
        self.last_child_ticked = 0
        return SKIPPED if skipped == len(self.child_nodes) else SUCCESS

    def halt(self) -> None:
        super().halt()
        self.last_child_ticked = 0


@control(ports=[input_port("wrap_around", bool, False, "Controls wrap-around behavior")])
class RoundRobin(Control):
    """Ticks one child per activation, the next one each time (Nav2's RoundRobinNode)."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current_child_idx = 0
        self.num_failed_children = 0
        self.wrap_around = bool(self.ports.get("wrap_around", bool))  # read once, in Nav2's constructor

    def bt_tick(self) -> Status:
        num_children = len(self.child_nodes)
        self.set_bt_status(RUNNING)
        num_skipped = 0
        while self.num_failed_children + num_skipped < num_children:
            status = self.tick_child(self.current_child_idx)
            if status is not RUNNING:
                self.current_child_idx += 1
                if self.current_child_idx == num_children:
                    if self.wrap_around:
                        self.current_child_idx = 0
                    else:
                        if status is SKIPPED:
                            num_skipped += 1
                        elif status is FAILURE:
                            self.num_failed_children += 1
                        break
            if status is SUCCESS:
                self.num_failed_children = 0
                self.halt_children()
                return SUCCESS
            if status is FAILURE:
                self.num_failed_children += 1
            elif status is SKIPPED:
                num_skipped += 1
            else:
                return RUNNING
        all_skipped = num_skipped == num_children
        self.halt()
        return SKIPPED if all_skipped else FAILURE

    def halt(self) -> None:
        super().halt()
        self.current_child_idx = 0
        self.num_failed_children = 0


@decorator(ports=[input_port("hz", float, 10.0, "Rate to throttle an action or a group of actions")])
class RateController(Decorator):
    """Ticks its child at the first tick of an activation, then again once 1/hz seconds of simulated time passed
    since it last succeeded; a RUNNING child is ticked every time."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.first_time = False
        self.start_ns = 0
        self.period_s = 1.0

    def bt_tick(self) -> Status:
        if self.bt_state is IDLE:  # Nav2: !isStatusActive(status()): a new activation (SKIPPED is never kept)
            self.period_s = 1.0 / (self.ports.get("hz", float) or 1.0)
            self.start_ns = self.clock.now_ns()
            self.first_time = True
        self.set_bt_status(RUNNING)
        elapsed_s = (self.clock.now_ns() - self.start_ns) / 1e9
        if self.first_time or self.child.bt_state is RUNNING or elapsed_s >= self.period_s:
            self.first_time = False
            status = self.tick_child()
            if status is SUCCESS:
                self.start_ns = self.clock.now_ns()
            return status
        return self.bt_state


def register(registry: NodeRegistry) -> None:
    for node in (RecoveryNode, PipelineSequence, RoundRobin, RateController):
        registry.register(node)
