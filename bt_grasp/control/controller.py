"""The controller a run's tick loop consults between ticks, and the queue front ends push commands into.

Threads: front ends (a terminal UI, the Foxglove server) call :meth:`Controller.send` and
:meth:`Controller.state` from any thread; the tick loop calls :meth:`Controller.between_ticks` after every
tick (and once before the first, with tick 0). Every command is applied there, at a tick boundary, never
inside a tick, in the order it arrived; an intervention is recorded with that boundary's tick. A paused run
waits inside ``between_ticks``: simulated time does not advance, and whatever runs in other threads (the live
server) keeps going.

The one exception is a ``node:`` breakpoint: the run holds *inside* the tick, just before the node's own tick
(through its pre-tick hook). While it holds only watching commands apply (resume, step, breakpoints);
interventions wait for the end of that tick's boundary, where they are applied and recorded.

``Controller(replay=records)`` applies recorded interventions again at their ticks (``replay --resim``).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Protocol

from bt_grasp.control.breakpoints import MAX_BREAKPOINTS, SOURCE, BreakKind, Breakpoint
from bt_grasp.control.commands import (
    ChooseObject,
    ClearBreakpoint,
    Command,
    CommandError,
    FireFault,
    Pause,
    Restart,
    Resume,
    SeedPolicy,
    SetBlackboard,
    SetBreakpoint,
    SetBreakpoints,
    Source,
    Step,
    Stop,
    command_from_json,
    command_to_json,
    is_intervention,
)
from bt_grasp.control.edits import choose_object, detections_in, names_a_file, reading_ports, set_entry
from bt_grasp.control.state import (
    DetectionView,
    FailureView,
    InterventionRecord,
    NodeView,
    RunState,
    value_text,
)
from bt_grasp.errors import InputError
from bt_grasp.tree.introspect import bt_status_name

if TYPE_CHECKING:
    from bt_grasp.tree.loader import LoadedTree
    from bt_grasp.tree.node import BtNode
    from bt_grasp.tree.runner import FailureEvent

log = logging.getLogger(__name__)

#: while the run goes, the view is rebuilt at most this often (wall time: it changes only what is shown)
VIEW_INTERVAL_S = 0.05



class InterventionSink(Protocol):
    """Where interventions are recorded (``RunRecorder.write_intervention``)."""

    def write_intervention(self, stamp_ns: int, record: Mapping[str, object]) -> None: ...


#: fires a fault of the catalogue now: (kind, params, tick) -> a sentence saying what fired; CommandError when
#: the kind or the parameters are wrong
FaultFirer = Callable[[str, Mapping[str, object], int], str]


class Controller:
    """One run's control: commands in, breakpoints, the run-state view out. Attach it to one run.

    Args:
        breakpoints: set before the first tick (``--break``).
        replay: recorded interventions to apply again at their ticks (``replay --resim``).
        start_paused: hold before the first tick (a front end shows the tree before anything moves).
        idle: called (with the state) when the run is paused and no command waits; it must send one. For
            scripted operators and tests; without it a paused run waits for a front end's command.
    """

    def __init__(
        self,
        breakpoints: Sequence[Breakpoint] = (),
        *,
        replay: Sequence[InterventionRecord] = (),
        start_paused: bool = False,
        idle: Callable[[RunState], None] | None = None,
        detections_entry: str = "objects",
    ) -> None:
        self._cond = threading.Condition()
        self._pending: deque[tuple[Command, Source]] = deque()
        self._deferred: list[tuple[Command, Source]] = []
        self._breakpoints: list[Breakpoint] = list(dict.fromkeys(breakpoints))
        self._replay: dict[int, list[InterventionRecord]] = {}
        for record in replay:
            self._replay.setdefault(record.tick, []).append(record)
        self._idle = idle
        self._detections_entry = detections_entry
        self._paused = start_paused
        self._pause_reason = "paused before the first tick" if start_paused else ""
        self._steps_left = 0
        self._stop = False
        self._finished = False
        self._tick = 0
        self._message = ""
        self._last_failure: FailureView | None = None
        self._bb_seen: dict[str, str] = {}
        self._last_time_s = -1.0  # simulated time at the last boundary (a time breakpoint fires on crossing)
        self._interventions: list[InterventionRecord] = []
        self._state = RunState(paused=start_paused, pause_reason=self._pause_reason,
                               breakpoints=tuple(b.spec for b in self._breakpoints))
        self._last_view = 0.0
        self._listeners: list[Callable[[RunState], None]] = []
        self._tree: LoadedTree | None = None
        self._now_ns: Callable[[], int] = lambda: 0
        self._sink: InterventionSink | None = None
        self._fire_fault: FaultFirer | None = None
        self._settings: tuple[str, ...] = ()
        self._file_settings: tuple[str, ...] = ()
        #: set by a Restart: the episode ended so that the caller starts the next one with this seed policy
        self.restart: SeedPolicy | None = None

    # ---- the front ends' side --------------------------------------------------------------------------
    def send(self, command: Command, source: Source = Source.API) -> None:
        """Queue a command (any thread); it takes effect at the next tick boundary (a paused run: now)."""
        with self._cond:
            self._pending.append((command, source))
            self._cond.notify_all()

    def state(self) -> RunState:
        """The latest view of the run (any thread)."""
        with self._cond:
            return self._state

    def subscribe(self, listener: Callable[[RunState], None]) -> None:
        """Call ``listener(state)`` from the tick loop's thread each time the view is rebuilt; it must not
        block (hand the state to the front end's own thread)."""
        self._listeners.append(listener)

    def wait(self, predicate: Callable[[RunState], bool], timeout_s: float) -> RunState:
        """Block until ``predicate(state)`` holds (or ``timeout_s``): tests and scripts; returns the state."""
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while not predicate(self._state):
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self._cond.wait(left)
            return self._state

    @property
    def interventions(self) -> tuple[InterventionRecord, ...]:
        return tuple(self._interventions)

    # ---- the tick loop's side ----------------------------------------------------------------------------
    def attach(
        self,
        tree: LoadedTree,
        now_ns: Callable[[], int],
        *,
        sink: InterventionSink | None = None,
        fire_fault: FaultFirer | None = None,
    ) -> None:
        """Wire the controller to a built tree before its first tick: node breakpoints hook every node's
        pre-tick (chained with a hook already there); ``--break node:X`` naming no node is an InputError."""
        self._tree, self._now_ns, self._sink, self._fire_fault = tree, now_ns, sink, fire_fault
        check_breakpoints(tree, self._breakpoints)
        for node in tree.nodes():
            self._hook(node)
        keys = list(tree.root_blackboard.keys())  # a Blackboard is not iterable
        self._settings = tuple(sorted(k for k in keys if self._is_setting(k)))
        self._file_settings = tuple(k for k in self._settings if names_a_file(k, reading_ports(tree, k)))
        self._remember_blackboard()

    def between_ticks(self, tick: int, failures: Sequence[FailureEvent] = ()) -> bool:
        """After tick ``tick`` (0: before the first): apply commands, pause as asked; True: stop the run."""
        self._tick = tick
        for event in failures:  # the view's last failure: the last one that was not false by design
            if not event.by_design:
                self._last_failure = FailureView(tick, event.leaf, event.path, event.reason, event.message)
        hit = self._hit(tick, failures)
        self._last_time_s = self._now_ns() * 1e-9
        if tick > 0 and self._steps_left:
            self._steps_left -= 1
            if self._steps_left == 0:
                self._paused, self._pause_reason = True, f"stepped to tick {tick}"
        if hit:
            self._paused, self._pause_reason, self._steps_left = True, hit, 0
        for record in self._replay.pop(tick, []):
            self._apply(command_from_json(record.command), Source.RESIM)
        deferred, self._deferred = self._deferred, []
        for command, source in deferred:
            self._apply(command, source)
        while True:
            commands = self._take()
            for command, source in commands:
                self._apply(command, source)
            self._remember_blackboard()
            self._publish(force=self._paused or self._stop or bool(hit) or bool(commands))
            if self._stop:
                return True
            if not self._paused:
                return False
            self._wait_for_command()

    def finish(self, tick: int | None = None) -> None:
        """The run ended (after ``tick``, its last: the result's tick count): the view says so (a front end may
        keep showing it). The tick loop consults no gate after the tick that ends the run, so the view's tick
        is the one before until this sets it."""
        if tick is not None:
            self._tick = tick
        self._finished, self._paused = True, False
        self._publish(force=True)

    # ---- commands ------------------------------------------------------------------------------------------
    def _take(self) -> list[tuple[Command, Source]]:
        with self._cond:
            taken = list(self._pending)
            self._pending.clear()
            return taken

    def _wait_for_command(self) -> None:
        if self._idle is not None:
            with self._cond:
                waiting = bool(self._pending)
            if not waiting:
                self._idle(self.state())
                with self._cond:
                    if not self._pending:
                        raise RuntimeError("the idle operator sent no command while the run was paused")
            return
        with self._cond:
            while not self._pending:
                self._cond.wait()

    def _apply(self, command: Command, source: Source) -> None:
        try:
            if is_intervention(command):
                self._intervene(command, source)
            else:
                self._watch(command, source)
        except CommandError as exc:
            self._message = str(exc)
            log.info("command %s refused: %s", type(command).__name__, exc)

    def _watch(self, command: Command, source: Source) -> None:
        if isinstance(command, Pause):
            if not self._paused:
                self._paused, self._pause_reason = True, f"paused ({source.value})"
            self._steps_left = 0
        elif isinstance(command, Resume):
            self._paused, self._steps_left, self._pause_reason = False, 0, ""
        elif isinstance(command, Step):
            self._paused, self._steps_left, self._pause_reason = False, command.n, ""
        elif isinstance(command, SetBreakpoint):
            if command.breakpoint.kind is BreakKind.NODE:
                self._check_node(command.breakpoint.target, CommandError)
            if command.breakpoint not in self._breakpoints:
                if len(self._breakpoints) >= MAX_BREAKPOINTS:
                    raise CommandError(f"a run holds at most {MAX_BREAKPOINTS} breakpoints; clear one first")
                self._breakpoints.append(command.breakpoint)
            self._message = f"breakpoint {command.breakpoint.spec} set"
        elif isinstance(command, SetBreakpoints):  # the set the controller holds now is replaced, whatever a view said
            for bp in command.breakpoints:
                if bp.kind is BreakKind.NODE:
                    self._check_node(bp.target, CommandError)
            self._breakpoints = list(dict.fromkeys(command.breakpoints))
            count = len(self._breakpoints)
            self._message = f"breakpoints set ({count})" if count else "breakpoints cleared"
        elif isinstance(command, ClearBreakpoint):
            if command.breakpoint is None:
                self._breakpoints.clear()
            elif command.breakpoint in self._breakpoints:
                self._breakpoints.remove(command.breakpoint)
            self._message = f"breakpoint {command.breakpoint.spec if command.breakpoint else '(all)'} cleared"

    def _intervene(self, command: Command, source: Source) -> None:
        tree = self._attached()
        recorded = command_to_json(command)
        if isinstance(command, SetBlackboard):
            stored = set_entry(tree, command.key, command.value)
            recorded["value"] = stored
            effect = f"{command.key} = {value_text(stored)}"
        elif isinstance(command, ChooseObject):
            index, chosen = choose_object(tree, command.choice, command.entry, command.detections)
            recorded["choice"] = index
            effect = f"{command.entry} = object {index} ({chosen.label})"
        elif isinstance(command, FireFault):
            if self._fire_fault is None:
                raise CommandError("this run has no fault injector, so no fault can be fired")
            effect = self._fire_fault(command.kind, command.params, self._tick)
        elif isinstance(command, Restart):
            self.restart, self._stop = command.seed, True
            effect = f"episode restarted with the {command.seed.value} seed"
        else:
            assert isinstance(command, Stop)
            self._stop = True
            effect = "run stopped"
        record = InterventionRecord(self._tick, int(self._now_ns()), source.value, recorded, effect)
        self._interventions.append(record)
        self._message = f"tick {self._tick}: {effect}"
        if self._sink is not None:
            self._sink.write_intervention(record.stamp_ns, record.to_json())

    # ---- breakpoints ---------------------------------------------------------------------------------------
    def _attached(self) -> LoadedTree:
        if self._tree is None:
            raise RuntimeError("the controller is not attached to a run")
        return self._tree

    def _check_node(self, target: str, error: type[Exception]) -> None:
        problem = _no_node(self._attached(), target)
        if problem:
            raise InputError(SOURCE, problem) if error is InputError else CommandError(problem)

    def _hook(self, node: BtNode) -> None:
        previous = node.bt_pre_tick

        def pre_tick(entering: BtNode) -> None:
            if any(b.kind is BreakKind.NODE and b.target in (entering.name, entering.bt_path)
                   for b in self._breakpoints) and entering.bt_state.value != "RUNNING":
                self._hold(f"before {entering.bt_path} (tick {self._tick + 1})")
            if previous is not None:
                previous(entering)

        node.bt_pre_tick = pre_tick

    def _hold(self, reason: str) -> None:
        """Hold inside a tick: only watching commands apply; interventions wait for the boundary."""
        self._paused, self._pause_reason, self._steps_left = True, reason, 0
        while True:
            for command, source in self._take():
                if is_intervention(command):
                    self._deferred.append((command, source))
                    self._message = (f"{command_to_json(command)['kind']} waits for the end of tick {self._tick + 1} "
                                     "(interventions apply between ticks)")
                    if isinstance(command, Stop | Restart):
                        self._paused = False  # finish this tick; the boundary stops the run
                else:
                    self._apply(command, source)
            self._publish(force=True)
            if not self._paused:
                if self._steps_left:  # the tick being finished is the first of the steps
                    self._steps_left += 1
                return
            self._wait_for_command()

    def _hit(self, tick: int, failures: Sequence[FailureEvent]) -> str:
        """Why a breakpoint stops the run after ``tick`` ('' when none does)."""
        now_s = self._now_ns() * 1e-9
        for bp in self._breakpoints:
            if bp.kind is BreakKind.TICK and bp.tick == tick:
                return f"breakpoint tick:{tick}"
            if bp.kind is BreakKind.TIME and self._last_time_s < bp.time_s <= now_s:
                return f"breakpoint {bp.spec} (t = {now_s:.3f} s)"
            if bp.kind is BreakKind.FAILURE:
                for event in failures:
                    if bp.stops_at(event.reason, event.by_design):
                        design = ", false by design" if event.by_design else ""
                        return f"breakpoint {bp.spec}: {event.path} failed ({event.reason or 'no reason'}{design})"
            if bp.kind is BreakKind.BLACKBOARD and tick > 0:
                text = self._entry_text(bp.target)
                if text != self._bb_seen.get(bp.target, text):
                    return f"breakpoint {bp.spec}: {bp.target} = {value_text(text)}"
        return ""

    def _entry_text(self, key: str) -> str:
        value = self._attached().root_blackboard.get(key, None)
        return repr(value)

    def _remember_blackboard(self) -> None:
        for bp in self._breakpoints:
            if bp.kind is BreakKind.BLACKBOARD:
                self._bb_seen[bp.target] = self._entry_text(bp.target)

    def _is_setting(self, key: str) -> bool:
        ports = reading_ports(self._attached(), key)
        return bool(ports) and all(spec.type in (str, int, float, bool) for _node, spec in ports)

    # ---- the view ------------------------------------------------------------------------------------------
    def _publish(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._last_view < VIEW_INTERVAL_S:
            return
        self._last_view = now
        tree = self._tree
        nodes: list[NodeView] = []
        blackboard: tuple[tuple[str, str], ...] = ()
        detections: tuple[DetectionView, ...] = ()
        status = "IDLE"
        if tree is not None:
            _views(tree.root, 0, nodes)
            blackboard = tuple((k, value_text(v)) for k, v in tree.root_blackboard.items().items())
            detections = tuple(
                DetectionView(i, str(d.label), tuple(float(x) for x in d.centroid_base_m),
                              tuple(float(x) for x in d.size_m))
                for i, d in enumerate(detections_in(tree, self._detections_entry)))
            status = tree.status.value
        state = RunState(
            tick=self._tick, sim_time_s=self._now_ns() * 1e-9, paused=self._paused,
            pause_reason=self._pause_reason if self._paused else "", finished=self._finished, nodes=tuple(nodes),
            blackboard=blackboard, last_failure=self._last_failure, detections=detections,
            breakpoints=tuple(b.spec for b in self._breakpoints), interventions=tuple(self._interventions),
            message=self._message, tree_status=status, settings=self._settings, file_settings=self._file_settings,
        )
        with self._cond:
            self._state = state
            self._cond.notify_all()
        for listener in self._listeners:
            listener(state)


def _no_node(tree: LoadedTree, target: str) -> str:
    if any(n.name == target or n.bt_path == target for n in tree.nodes()):
        return ""
    names = sorted({n.name for n in tree.nodes()})
    return f"'node:{target}' names no node of the tree; nodes: {', '.join(names)}"


def check_breakpoints(tree: LoadedTree, breakpoints: Sequence[Breakpoint]) -> None:
    """InputError (``--break``, one sentence) when a ``node:`` breakpoint names no node of ``tree``."""
    for bp in breakpoints:
        problem = _no_node(tree, bp.target) if bp.kind is BreakKind.NODE else ""
        if problem:
            raise InputError(SOURCE, problem)


def _views(node: BtNode, depth: int, out: list[NodeView]) -> None:
    out.append(NodeView(node.bt_path, node.name, node.bt_type, bt_status_name(node), depth))
    for child in getattr(node, "children", ()):
        _views(child, depth + 1, out)
