"""Stand-ins for other projects' nodes, written the way a user writes a bt_grasp plugin: only against the
public API (``bt_grasp.nodes``), loaded with ``--leaves`` (``bt-grasp tree run --dry --leaves standins.py``).

They are the twins of the C++ stand-ins the differential driver registers in BehaviorTree.CPP
(``tools/btcpp_diff/standins.hpp``); keep the two equal. The "world" a stand-in acts on lives in the root
blackboard (``@door_open``, ``@planner_failures``, ...), set by the tree's own scripts; durations are counted in
ticks, so no stand-in reads a clock. Shapes: BT.CPP's tutorials (SaySomething, ThinkWhatToSay,
CalculateGoal/PrintTarget with a custom port type, BatteryOK/MoveBase, the CrossDoor nodes) and Nav2's
navigation trees (ComputePathToPose, FollowPath, ClearEntireCostmap, GoalUpdated, Spin, Wait, BackUp,
RecoveryNode, PipelineSequence, RoundRobin, RateController, GoalUpdater).
"""

from __future__ import annotations

from typing import Any

from bt_grasp.nodes import (
    Control,
    Decorator,
    Leaf,
    NodeContext,
    NodeRegistry,
    Status,
    action,
    condition,
    control,
    decorator,
    input_port,
    output_port,
)

RUNNING, SUCCESS, FAILURE, SKIPPED, IDLE = (
    Status.RUNNING,
    Status.SUCCESS,
    Status.FAILURE,
    Status.SKIPPED,
    Status.IDLE,
)


class Position2D:
    """A 2-D position written ``x;y`` in a tree file (BT.CPP tutorial 3's custom port type)."""

    def __init__(self, x: float, y: float) -> None:
        self.x, self.y = x, y

    @classmethod
    def from_port_text(cls, text: str) -> Position2D:
        parts = text.split(";")
        if len(parts) != 2:
            raise ValueError("invalid input)")
        return cls(float(parts[0]), float(parts[1]))


def root_value(node: Any, key: str, fallback: Any) -> Any:
    value = node.blackboard.get("@" + key, None)
    return fallback if value is None else type(fallback)(value)


def set_root(node: Any, key: str, value: Any) -> None:
    node.blackboard.set("@" + key, value)


def say(node: Any, text: str) -> None:
    """Appends ``text`` to the root entry ``said`` (``a|b|c``): what the robot said, for the comparison."""
    said = root_value(node, "said", "")
    set_root(node, "said", f"{said}|{text}" if said else text)


def take_one(node: Any, key: str) -> bool:
    """Takes one from a positive integer root entry; True when it did (a scripted failure is due)."""
    left = root_value(node, key, 0)
    if left <= 0:
        return False
    set_root(node, key, left - 1)
    return True


# ---------------------------------------------------------------- BT.CPP tutorials


@action(ports=[input_port("message", str)])
class SaySomething(Leaf):
    """Says the message."""

    def update(self) -> Status:
        say(self, self.ports.require("message", str))
        return Status.SUCCESS


@action(ports=[output_port("text", str)])
class ThinkWhatToSay(Leaf):
    """Thinks of an answer."""

    def update(self) -> Status:
        self.ports.set("text", "The answer is 42")
        return Status.SUCCESS


@action(ports=[output_port("goal", Position2D)])
class CalculateGoal(Leaf):
    """Computes a goal."""

    def update(self) -> Status:
        self.ports.set("goal", Position2D(1.1, 2.3))
        return Status.SUCCESS


@action(ports=[input_port("target", Position2D)])
class PrintTarget(Leaf):
    """Says the target."""

    def update(self) -> Status:
        target = self.ports.require("target", Position2D)
        say(self, f"target {target.x:.1f} {target.y:.1f}")
        return Status.SUCCESS


@condition(ports=[input_port("level", int, "{battery}", "charge in percent")])
class BatteryOK(Leaf):
    """SUCCESS while the battery is at least 20."""

    def update(self) -> Status:
        return Status.SUCCESS if self.ports.require("level", int) >= 20 else Status.FAILURE


@action(ports=[input_port("goal", Position2D), input_port("steps", int, 2, "ticks to arrive")])
class MoveBase(Leaf):
    """Drives to the goal in `steps` ticks."""

    def initialise(self) -> None:
        self.ports.require("goal", Position2D)
        self.done = -1  # BT.CPP's onStart returns RUNNING without counting a step

    def update(self) -> Status:
        self.done += 1
        if self.done == 0:
            return Status.RUNNING
        if self.done >= self.ports.require("steps", int):
            set_root(self, "moves", root_value(self, "moves", 0) + 1)
            return Status.SUCCESS
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:
            set_root(self, "move_halts", root_value(self, "move_halts", 0) + 1)


@condition()
class IsDoorClosed(Leaf):
    """SUCCESS while the door is closed."""

    def update(self) -> Status:
        return Status.FAILURE if root_value(self, "door_open", False) else Status.SUCCESS


@action()
class PassThroughDoor(Leaf):
    """Walks through an open door."""

    def update(self) -> Status:
        if not root_value(self, "door_open", False):
            return Status.FAILURE
        set_root(self, "passed", True)
        return Status.SUCCESS


@action()
class OpenDoor(Leaf):
    """Opens an unlocked door."""

    def update(self) -> Status:
        if root_value(self, "door_locked", False):
            return Status.FAILURE
        set_root(self, "door_open", True)
        return Status.SUCCESS


@action()
class PickLock(Leaf):
    """Opens the lock at the third attempt."""

    def update(self) -> Status:
        attempts = root_value(self, "pick_attempts", 0) + 1
        set_root(self, "pick_attempts", attempts)
        if attempts < 3:
            return Status.FAILURE
        set_root(self, "door_locked", False)
        set_root(self, "door_open", True)
        return Status.SUCCESS


@action()
class SmashDoor(Leaf):
    """Never works."""

    def update(self) -> Status:
        return Status.FAILURE


# ---------------------------------------------------------------- Nav2-like nodes


@action(
    ports=[
        input_port("goal", str),
        input_port("planner_id", str, "GridBased"),
        output_port("path", str),
        output_port("error_code_id", int),
    ]
)
class ComputePathToPose(Leaf):
    """One tick of RUNNING, then a path to the goal; fails while @planner_failures > 0."""

    def initialise(self) -> None:
        self.started = False

    def update(self) -> Status:
        if not self.started:
            self.started = True
            return Status.RUNNING
        set_root(self, "plans", root_value(self, "plans", 0) + 1)
        if take_one(self, "planner_failures"):
            self.ports.set("error_code_id", 204)
            return Status.FAILURE
        self.ports.set("path", f"{self.ports.require('planner_id', str)}:{self.ports.require('goal', str)}")
        self.ports.set("error_code_id", 0)
        return Status.SUCCESS


@action(
    ports=[input_port("path", str), input_port("controller_id", str, "FollowPath"), output_port("error_code_id", int)]
)
class FollowPath(Leaf):
    """RUNNING for @follow_ticks ticks (2 when unset), then SUCCESS; fails while @follow_failures > 0."""

    def initialise(self) -> None:
        self.done = -1

    def update(self) -> Status:
        if self.done < 0:
            if not self.ports.require("path", str):
                return Status.FAILURE
            self.done = 0
            return Status.RUNNING
        self.done += 1
        if self.done < root_value(self, "follow_ticks", 2):
            return Status.RUNNING
        if take_one(self, "follow_failures"):
            self.ports.set("error_code_id", 106)
            return Status.FAILURE
        set_root(self, "arrivals", root_value(self, "arrivals", 0) + 1)
        self.ports.set("error_code_id", 0)
        return Status.SUCCESS

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:
            set_root(self, "follow_halts", root_value(self, "follow_halts", 0) + 1)


@action(ports=[input_port("service_name", str)])
class ClearEntireCostmap(Leaf):
    """Counts the clears in @clears."""

    def update(self) -> Status:
        set_root(self, "clears", root_value(self, "clears", 0) + 1)
        return Status.SUCCESS


@condition()
class GoalUpdated(Leaf):
    """SUCCESS once per pending @goal_updates."""

    def update(self) -> Status:
        return Status.SUCCESS if take_one(self, "goal_updates") else Status.FAILURE


class _Behavior(Leaf):
    """A recovery behaviour: RUNNING for `ticks` ticks, then SUCCESS (FAILURE while @<type>_failures > 0)."""

    def ticks(self) -> int:
        raise NotImplementedError

    def initialise(self) -> None:
        self.done = -1

    def update(self) -> Status:
        self.done += 1
        if self.done < self.ticks():
            return Status.RUNNING
        if take_one(self, f"{self.bt_type}_failures"):
            return Status.FAILURE
        say(self, self.bt_type)
        return Status.SUCCESS

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:
            say(self, f"halted {self.bt_type}")


@action(ports=[input_port("spin_dist", float, 1.57, "rad")])
class Spin(_Behavior):
    """Spins in place."""

    def ticks(self) -> int:
        return 1


@action(ports=[input_port("wait_duration", float, 1.0, "seconds (one tick each)")])
class Wait(_Behavior):
    """Waits."""

    def ticks(self) -> int:
        return int(self.ports.require("wait_duration", float))


@action(ports=[input_port("backup_dist", float, 0.15, "m"), input_port("backup_speed", float, 0.025, "m/s")])
class BackUp(_Behavior):
    """Backs up."""

    def ticks(self) -> int:
        return 0


@control(ports=[input_port("number_of_retries", int, 1)], children=(2, 2))
class RecoveryNode(Control):
    """Ticks the second child on the first's failure, then the first again, at most number_of_retries times."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.retry_count = 0

    def bt_tick(self) -> Status:
        retries = self.ports.require("number_of_retries", int)
        self.set_bt_status(RUNNING)
        while self.current < 2 and self.retry_count <= retries:
            status = self.tick_child(self.current)
            if self.current == 0:
                if status in (SKIPPED, SUCCESS):
                    self.halt()
                    return status
                if status is RUNNING:
                    return RUNNING
                if self.retry_count < retries:
                    self.halt_child(0)
                    self.current = 1
                    continue
                self.halt()
                return FAILURE
            if status is RUNNING:
                return RUNNING
            if status is SUCCESS:
                self.halt_child(1)
                self.retry_count += 1
                self.current = 0
                continue
            self.halt()
            return FAILURE
        self.halt()
        return FAILURE

    def halt(self) -> None:
        super().halt()
        self.retry_count = 0
        self.current = 0


@control()
class PipelineSequence(Control):
    """Ticks every child from the first each tick; a child before the RUNNING one may be RUNNING too."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.last_running = 0

    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        for index in range(len(self.child_nodes)):
            status = self.tick_child(index)
            if status is FAILURE:
                self.halt_children()
                self.last_running = 0
                return FAILURE
            if status is RUNNING and index >= self.last_running:
                self.last_running = index
                return RUNNING
        self.halt_children()
        self.last_running = 0
        return SUCCESS

    def halt(self) -> None:
        super().halt()
        self.last_running = 0


@control()
class RoundRobin(Control):
    """Ticks one child per activation, the next one each time; FAILURE when every child failed in a row."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.current = 0
        self.failed = 0

    def bt_tick(self) -> Status:
        count = len(self.child_nodes)
        self.set_bt_status(RUNNING)
        skipped = 0
        while self.failed + skipped < count:
            status = self.tick_child(self.current)
            if status is not RUNNING:
                self.current = (self.current + 1) % count
            if status is SUCCESS:
                self.failed = 0
                self.halt_children()
                return SUCCESS
            if status is RUNNING:
                return RUNNING
            if status is FAILURE:
                self.failed += 1
            else:
                skipped += 1
        self.halt_children()
        self.failed = 0
        return FAILURE

    def halt(self) -> None:
        super().halt()
        self.failed = 0


@decorator(ports=[input_port("period", int, 3, "ticks between two runs of the child")])
class RateController(Decorator):
    """Ticks the child at its first tick, then once `period` ticks passed since its last success."""

    def __init__(self, ctx: NodeContext) -> None:
        super().__init__(ctx)
        self.first = True
        self.since = 0

    def bt_tick(self) -> Status:
        if self.bt_state is IDLE:
            self.first = True
            self.since = 0
        self.set_bt_status(RUNNING)
        self.since += 1
        if self.first or self.child.bt_state is RUNNING or self.since >= self.ports.require("period", int):
            self.first = False
            status = self.tick_child()
            if status is SUCCESS:
                self.since = 0
            return status
        return RUNNING


@decorator(ports=[input_port("input_goal", str), output_port("output_goal", str)])
class GoalUpdater(Decorator):
    """Writes @goal_update (when set), else input_goal, to output_goal, then ticks the child."""

    def bt_tick(self) -> Status:
        self.set_bt_status(RUNNING)
        goal = self.ports.require("input_goal", str)
        update = root_value(self, "goal_update", "")
        self.ports.set("output_goal", update or goal)
        status = self.tick_child()
        if status is not RUNNING:
            self.reset_child()
        return status


NODES = (
    SaySomething, ThinkWhatToSay, CalculateGoal, PrintTarget, BatteryOK, MoveBase, IsDoorClosed, PassThroughDoor,
    OpenDoor, PickLock, SmashDoor, ComputePathToPose, FollowPath, ClearEntireCostmap, GoalUpdated, Spin, Wait,
    BackUp, RecoveryNode, PipelineSequence, RoundRobin, RateController, GoalUpdater,
)


def register(registry: NodeRegistry) -> None:
    for node in NODES:
        registry.register(node)
    registry.register_enums({"DOCKED": 0, "NAVIGATING": 1, "RECOVERING": 2})
