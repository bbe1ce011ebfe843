"""Installing a fault plan on a prepared run: wrap the interfaces, watch leaf entries and ticks, arm faults.

The injector never touches tree results or blackboard entries. It wraps ``cell.camera``, ``cell.robot``,
``cell.planner`` and ``cell.kinematics`` (and, when an offset fires,
``cell.calibration``), and it changes physics through the simulator's physics hook. Leaf entries are seen
through each leaf's pre-tick hook (``BtNode.bt_pre_tick``): it only arms a fault; the fault then acts on
the interfaces. Nothing of a leaf is replaced.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bt_grasp.errors import InputError
from bt_grasp.faults.armed import ArmedFault
from bt_grasp.faults.camera import FaultyCamera
from bt_grasp.faults.effects import SERVICE_KINDS, START, Wrapped
from bt_grasp.faults.firing import FaultFiring
from bt_grasp.faults.model import FaultKind, ObjectNudgeParams, ServiceFailParams
from bt_grasp.faults.plan import Fault, FaultPlan
from bt_grasp.faults.robot import FaultyRobot
from bt_grasp.faults.services import FaultyKinematics, FaultyPlanner
from bt_grasp.faults.site import FaultSite
from bt_grasp.tree.node import BtNode, BtStatus

log = logging.getLogger(__name__)

LEAF_KINDS = ("Action", "Condition")


class FaultRecorder(Protocol):
    def write_fault(self, stamp_ns: int, tick: int, fault: Mapping[str, object]) -> None: ...


@dataclass
class _Armed:
    """A fault of the plan and its trigger's state."""

    fault: Fault
    index: int
    entries: int = 0  # entries of the trigger's leaf seen so far
    armed: int = 0  # episodes started (at most fault.count)
    current: ArmedFault | None = None

    def may_arm(self) -> bool:
        return self.armed < self.fault.count and (self.current is None or self.current.done)


def _matches(node: BtNode, name: str) -> bool:
    return name in (node.name, getattr(node, "bt_type", None), getattr(node, "bt_path", None))


def _is_leaf(node: BtNode) -> bool:
    kind = getattr(node, "bt_kind", None)
    return getattr(kind, "value", kind) in LEAF_KINDS


class Injector:
    """Arms the plan's faults as their triggers come and records every firing."""

    def __init__(self, plan: FaultPlan, wrapped: Wrapped, leaves: list[BtNode],
                 recorder: FaultRecorder | None) -> None:
        self.plan = plan
        self.wrapped = wrapped
        self.recorder = recorder
        self.leaves = leaves
        self.fired = 0
        self.firings: list[dict[str, object]] = []
        self._tick = 0  # the last tick finished
        self._in_after_tick = False
        self._faults = [_Armed(f, i) for i, f in enumerate(plan.faults)]
        #: the objects a finger touched so far, watched (after every tick) only when a fault may push one
        self.touched: set[str] = set()
        self._watch_touches = any(f.kind is FaultKind.OBJECT_NUDGE for f in plan.faults)
        #: the run's fault stream (``install_faults`` sets it): faults fired by hand draw from it too
        self.seed_sequence: np.random.SeedSequence | None = None
        check_fault_plan(plan, leaves, None)
        for node in leaves:
            self._hook(node)

    def _hook(self, node: BtNode) -> None:
        """Watch the leaf's entries through the tree's pre-tick hook (kept chained if one is set)."""
        previous: Callable[[BtNode], None] | None = node.bt_pre_tick

        def pre_tick(entering: BtNode) -> None:
            if previous is not None:
                previous(entering)
            if entering.bt_state is not BtStatus.RUNNING:  # the tick starts a new attempt of the leaf
                self._entered(entering)

        node.bt_pre_tick = pre_tick

    # --- triggers ---------------------------------------------------------------------------------------
    def _entered(self, node: BtNode) -> None:
        self.wrapped.apply_calibration_offsets()
        self._end_finished_attempts()  # a tree may fail, recover and retry within one tick
        for armed in self._faults:
            trigger = armed.fault.trigger
            if trigger.at_tick is not None:
                continue
            if trigger.on_leaf is not None and not _matches(node, trigger.on_leaf):
                continue
            armed.entries += 1
            if not armed.may_arm():
                continue
            if trigger.probability is not None:
                if self.wrapped.rngs[armed.index].random() >= trigger.probability:
                    continue
            elif armed.entries < (trigger.nth or 1):
                continue
            self._arm(armed, node)

    def before_run(self) -> None:
        """Called once before the first tick."""
        self.wrapped.apply_calibration_offsets()

    def after_tick(self, tick: int) -> None:
        """Called after every tick: tick triggers, timers, episodes that end with their leaf's attempt."""
        self._tick = tick
        if self._watch_touches:
            self.touched |= self.wrapped.physics.objects_touching_fingers()
        self._in_after_tick = True
        try:
            self._after_tick(tick)
        finally:
            self._in_after_tick = False

    def fire_now(self, fault: Fault, tick: int) -> None:
        """Arm ``fault`` at the boundary after ``tick`` as a ``tick:`` trigger would (an operator's FireFault;
        ``bt_grasp.control``); its random draws come from its own stream, numbered after the plan's."""
        check_fault_plan(FaultPlan((fault,)), self.leaves, list(self.wrapped.physics.object_names()))
        index = len(self._faults)
        if self.seed_sequence is not None:
            seq = self.seed_sequence
            self.wrapped.rngs[index] = np.random.default_rng(
                np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, index)))
        armed = _Armed(fault, index)
        self._faults.append(armed)
        self._watch_touches |= fault.kind is FaultKind.OBJECT_NUDGE
        self._tick = tick
        self._in_after_tick = True
        try:
            self._arm(armed, None)
        finally:
            self._in_after_tick = False

    def report(self) -> tuple[FaultFiring, ...]:
        """Every firing so far, in order, with the object each push hit and whether the tree touched it."""
        out = []
        for record in self.firings:
            details = record.get("details")
            target = details.get("object") if isinstance(details, dict) else None
            name = target if isinstance(target, str) else None
            tick, leaf = record.get("tick"), record.get("leaf")
            out.append(FaultFiring(str(record.get("label")), str(record.get("kind")), tick if isinstance(tick, int)
                                   else 0, leaf if isinstance(leaf, str) else None, name,
                                   None if name is None else name in self.touched))
        return tuple(out)

    def close(self) -> None:
        """The run ended: undo what is still pending (a weakened grip's friction), so a world reused for
        the next episode starts as built."""
        pending, self.wrapped.timers = self.wrapped.timers, []
        for timer in pending:
            timer.action()

    def _current_tick(self) -> int:
        """The tick a firing belongs to: the one running, or the one just finished (in after_tick)."""
        return self._tick if self._in_after_tick else self._tick + 1

    def _after_tick(self, tick: int) -> None:
        now = self.wrapped.now_ns()
        due = [t for t in self.wrapped.timers if t.at_ns <= now]
        self.wrapped.timers = [t for t in self.wrapped.timers if t.at_ns > now]
        for timer in due:
            timer.action()
        self.wrapped.robot.expire()
        self._end_finished_attempts()
        for armed in self._faults:
            trigger = armed.fault.trigger
            if trigger.at_tick is not None and tick >= trigger.at_tick and armed.may_arm():
                self._arm(armed, None)
        self.wrapped.apply_calibration_offsets()

    def _end_finished_attempts(self) -> None:
        for armed in self._faults:
            ep = armed.current
            if ep is not None and not ep.done and self._attempt_over(ep):
                ep.finish()

    @staticmethod
    def _attempt_over(ep: ArmedFault) -> bool:
        """A ``within_attempt`` service fault armed by a leaf whose attempt has ended."""
        params = ep.fault.params
        if ep.node is None or ep.fault.kind not in SERVICE_KINDS or not isinstance(params, ServiceFailParams) \
                or not params.within_attempt:
            return False
        return getattr(ep.node.bt_state, "value", "") != "RUNNING"

    # --- arming and recording --------------------------------------------------------------------------
    def _arm(self, armed: _Armed, node: BtNode | None) -> None:
        leaf = None if node is None else node.name
        tick = self._current_tick()
        arming = ArmedFault(armed.fault, tick, leaf, node, self._record)
        armed.current = arming
        armed.armed += 1
        log.info("fault %s armed (tick %d%s)", armed.fault.label, tick, f", entering {leaf}" if leaf else "")
        START[armed.fault.kind](arming, self.wrapped, armed.index)

    def _record(self, arming: ArmedFault, details: dict[str, object]) -> None:
        self.fired += 1
        fault = arming.fault
        tick = self._current_tick()
        record: dict[str, object] = {
            **fault.to_dict(),
            "leaf": arming.leaf,
            "armed_tick": arming.tick,
            "firing": self.fired,
            "details": details,
        }
        self.firings.append({"tick": tick, **record})
        log.warning("fault %s fired at tick %d: %s", fault.label, tick, details.get("effect", ""))
        if self.recorder is not None:
            self.recorder.write_fault(self.wrapped.now_ns(), tick, record)


def check_fault_plan(plan: FaultPlan, leaves: Sequence[BtNode], object_names: Sequence[str] | None) -> None:
    """InputError (naming the plan's file and fault) when a trigger names no leaf of the tree or a nudge
    names no object of the scene: checked before anything is built."""
    names = sorted({n.name for n in leaves})
    for fault in plan.faults:
        wanted = fault.trigger.on_leaf
        if wanted is not None and not any(_matches(n, wanted) for n in leaves):
            raise InputError(
                fault.source, f"on_leaf '{wanted}' names no leaf of the tree; leaves: {', '.join(names)}", fault.where
            )
        name = fault.params.object if isinstance(fault.params, ObjectNudgeParams) else None
        if object_names is not None and name is not None and name not in object_names:
            known = ", ".join(object_names)
            raise InputError(fault.source, f"no object '{name}' in the scene; objects: {known}", fault.where)


def leaves_of(nodes: Sequence[BtNode]) -> list[BtNode]:
    return [n for n in nodes if _is_leaf(n)]


def _fault_rngs(seq: np.random.SeedSequence, plan: FaultPlan) -> dict[int, np.random.Generator]:
    """One generator per fault, derived from the run's fault stream (independent of the plan's length)."""
    return {
        i: np.random.default_rng(np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, i)))
        for i in range(len(plan.faults))
    }


def install_faults(plan: FaultPlan, site: FaultSite, recorder: FaultRecorder | None) -> Injector:
    """Wrap the prepared run's cell and tree for ``plan``; call before the leaves' ``setup``."""
    cell = site.cell
    camera = FaultyCamera(cell.camera)
    robot = FaultyRobot(cell.robot, cell.clock)
    planner = FaultyPlanner(cell.planner)
    kinematics = FaultyKinematics(cell.kinematics)
    cell.camera, cell.robot = camera, robot
    cell.planner, cell.kinematics = planner, kinematics
    color = None
    root_blackboard = site.tree.root_blackboard
    if root_blackboard.has("color"):
        value = root_blackboard.get("color")
        color = value if isinstance(value, str) else None  # a colour is a name; nothing else matches an object
    rngs = _fault_rngs(site.fault_seed_sequence, plan)
    wrapped = Wrapped(cell, site.physics, camera, robot, planner, kinematics, rngs, color=color)
    leaves = leaves_of(list(site.tree.nodes()))
    check_fault_plan(plan, leaves, list(site.physics.object_names()))
    injector = Injector(plan, wrapped, leaves, recorder)
    injector.seed_sequence = site.fault_seed_sequence
    log.info("installed %d fault(s) on %d leaves", len(plan.faults), len(leaves))
    return injector
