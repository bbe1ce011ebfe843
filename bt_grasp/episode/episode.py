"""One episode: validate every input, build (or reuse) the world, run the tree to the end, judge, summarise.

This is the composition root of a run: the only place where the simulator, the pipeline services, the tree,
the fault plan, the recorder and the judge meet. ``bt-grasp run``/``demo``/``replay --resim``, benchmarks,
evaluation workers and notebooks call it; it never prints (callbacks see every tick).
"""

from __future__ import annotations

import logging
import re
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.episode.request import BlackboardValue, EpisodeRequest
from bt_grasp.episode.result import GOAL_NOT_MET, ChainStep, EpisodeResult, Judged, interrupted_result
from bt_grasp.episode.worlds import FreshWorlds, WorldSource
from bt_grasp.errors import InputError
from bt_grasp.scene.goals import CollectGoal, Goal, PickGoal
from bt_grasp.scene.run_goal import goal_for_run

if TYPE_CHECKING:
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.control.controller import Controller, FaultFirer
    from bt_grasp.episode.cell_assembly import CellDevices
    from bt_grasp.episode.instruments import TimedPlanner
    from bt_grasp.faults.injector import Injector
    from bt_grasp.faults.physics import PhysicsHook
    from bt_grasp.faults.plan import FaultPlan
    from bt_grasp.foxglove.live import LiveServer
    from bt_grasp.perception.calibration_file import CalibrationFile
    from bt_grasp.recording.writer import RunRecorder
    from bt_grasp.scene.format import Scene
    from bt_grasp.sim.judge import Verdict
    from bt_grasp.sim.world import World
    from bt_grasp.tree.loader import LoadedTree
    from bt_grasp.tree.records import NodeRecord
    from bt_grasp.tree.runner import FailureEvent, TickRecorder

log = logging.getLogger(__name__)

#: the log's chunk is ended (handed to the OS) every this many ticks: a killed run loses at most the ticks since.
#: Counted in ticks, not wall time, so the same seed gives the same file bytes on any machine (issue 27).
LOG_FLUSH_EVERY_TICKS = 20

#: called after every tick with the tick's number and the tree (progress bars, live views, logging)
TickCallback = Callable[[int, "LoadedTree"], None]


class _EpisodeClock:
    """The tree's clock: the world's, once the world exists (the tree is loaded and checked first)."""

    def __init__(self) -> None:
        self.world: World | None = None

    def now_ns(self) -> int:
        return 0 if self.world is None else self.world.clock.now_ns()


@dataclass(frozen=True)
class Inputs:
    """Every input file read and checked: nothing is built yet."""

    scene: Scene
    tree: LoadedTree
    calibration_path: Path | None  # --calibration, else the file the scene names beside it
    calibration: CalibrationFile | None
    goal: Goal
    fault_plan: FaultPlan | None
    clock: _EpisodeClock


def load_inputs(request: EpisodeRequest) -> Inputs:
    """Read and check every input of ``request``; raises InputError (or a ConfigError) naming the file."""
    from bt_grasp.behaviours import robot_registry
    from bt_grasp.behaviours.library import check_tree_against_scene
    from bt_grasp.scene.format import load_scene
    from bt_grasp.tree.loader import load_tree

    scene = load_scene(request.scene)
    goal = request.goal if request.goal is not None else goal_for_run(scene, request.blackboard)
    check_goal(goal, scene, request.scene, given=request.goal is not None)
    from bt_grasp.perception.calibration_file import calibration_for_scene

    # --calibration, else the file the scene names beside it; another mount or camera pose is bad input
    calibration_path, calibration = calibration_for_scene(scene, request.scene, request.calibration)
    clock = _EpisodeClock()
    tree = load_tree(request.tree, robot_registry(request.leaves), clock=clock)
    check_tree_against_scene(tree.nodes(), scene)
    fault_plan = None
    if request.faults is not None or request.inject:
        from bt_grasp.faults.injector import check_fault_plan, leaves_of
        from bt_grasp.faults.plan import load_fault_plan

        fault_plan = load_fault_plan(request.faults, request.inject)
        check_fault_plan(fault_plan, leaves_of(list(tree.nodes())), [o.name for o in scene.objects])
    if request.max_ticks < 1:
        raise InputError("--max-ticks", f"must be at least 1, got {request.max_ticks}")
    _check_log_path(request.log, (request.tree, request.scene, request.calibration, request.faults))
    return Inputs(scene, tree, calibration_path, calibration, goal, fault_plan, clock)


def _check_log_path(log_path: Path | None, inputs: tuple[Path | None, ...] = ()) -> None:
    """The log must be a file that can be created (``bt_grasp.files.output_files``): a folder, a device or FIFO, a
    symbolic link, or a place where nothing can be written is bad input before anything runs (each was a
    traceback or a hang, some only after the run)."""
    if log_path is None:
        return
    from bt_grasp.files.output_files import check_output_file

    check_output_file(log_path, "--log", example="run.mcap", inputs=inputs)  # never over the run's own inputs


def check_goal(goal: Goal, scene: Scene, scene_path: Path, *, given: bool) -> None:
    """The judge can check ``goal`` on ``scene`` (read from ``scene_path``): InputError (naming ``--goal`` when the
    goal was ``given``, else the scene) when no checker exists, or a pick's colour is no object's colour.
    ``bt-grasp run`` and ``scene validate`` ask this of the same goal."""
    from bt_grasp.sim.judge import cannot_judge

    problem = cannot_judge(goal)
    if problem is not None:
        raise InputError("--goal" if given else scene_path, problem)
    if isinstance(goal, PickGoal) and goal.color and goal.object is None:
        colors = sorted({str(o.color) for o in scene.objects if o.color is not None})
        if goal.color not in colors:
            raise InputError("--color", f"the pick goal's colour '{goal.color}' is not the colour of any object "
                                        f"of {scene_path} (colours there: {', '.join(colors) or 'none named'}); "
                                        "give --color '' to pick any object")


class Episode:
    """A prepared episode: inputs checked, world built or reset, cell and tree wired. ``run()`` once."""

    def __init__(self, request: EpisodeRequest, worlds: WorldSource | None = None) -> None:
        self.request = request
        self.inputs = load_inputs(request)  # bad input stops here: nothing built, nothing written
        if request.log is not None:
            from bt_grasp.recording.writer_process import prestart

            prestart()  # the log's writer process starts (and imports) while the world is built, not in the run
        self.scene = self.inputs.scene
        self.tree = self.inputs.tree
        self.world: World = (worlds or FreshWorlds()).world_for(self.scene, request.seed, request.scene)
        self.inputs.clock.world = self.world
        for key, value in {**goal_entries(self.inputs.goal), **request.blackboard}.items():
            self.tree.root_blackboard.set(key, value)
        if self.inputs.calibration_path is not None:
            self.tree.root_blackboard.set("calibration_file", str(self.inputs.calibration_path))
        self.devices = self._devices()
        #: the run's cell and planning statistics: assembled when the run starts (``cell_assembly``)
        self.cell: Cell
        self.planning: TimedPlanner
        self._injector: Injector | None = None
        self._ran = False
        self.live: LiveServer | None = None
        #: called with the live view's URL once its server listens (the CLI prints how to connect)
        self.on_live: list[Callable[[str], None]] = []
        #: called as it happens with every leaf FAILURE that is not by design (the CLI's live failure line)
        self.on_failure: list[Callable[[FailureEvent], None]] = []

    def _failure_seen(self, event: FailureEvent) -> None:
        for callback in self.on_failure:
            callback(event)

    def _devices(self) -> CellDevices:
        """The simulated cell's devices (the calibration board mounted on the gripper when a leaf needs it)."""
        from bt_grasp.behaviours.calibration_leaves import needs_calibration_board
        from bt_grasp.episode.cell_assembly import CellDevices

        world = self.world
        board = None
        if needs_calibration_board(self.tree.nodes()):
            from bt_grasp.sim.charuco import mount_calibration_board

            board = mount_calibration_board(world)
        latency = self.request.perception_latency_s
        return CellDevices(world.robot, world.camera, world.clock, board,
                           perception_latency_s=self.scene.latency_s if latency is None else latency,
                           encoders=world.encoders)

    def run(self, on_tick: Sequence[TickCallback] = (), controller: Controller | None = None) -> EpisodeResult:
        """Tick the tree to the end (or ``max_ticks``), judge the goal, write the result; returns it.

        ``controller``: an interactive run (``bt_grasp.control``): consulted between ticks, it may pause, stop
        and intervene; a fault injector is installed (with no fault planned: nothing changes until one is fired
        by hand) and interventions are recorded. Without one the run is exactly the plain run."""
        from bt_grasp.sim.judge import Judge
        from bt_grasp.tree.runner import TreeRunner

        if self._ran:
            raise RuntimeError("an Episode runs once; prepare a new one (a WarmWorlds source reuses the world)")
        self._ran = True
        request, world = self.request, self.world
        judge = Judge(world)
        recorder = self._open_recorder()
        observers: list[TickCallback] = []
        extras = None
        injector: Injector | None = None
        ticked = [0]  # the last tick started (an interrupted run's result says where it stopped)
        try:
            cell = self._assemble(recorder, controller)
            injector = self._injector
            if recorder is not None:
                from bt_grasp.episode.observers import LogExtras

                extras = LogExtras(recorder, world, cell, request.image_hz)
                extras.start()
                observers.append(extras)
            if request.realtime is not None:
                from bt_grasp.episode.observers import RealtimePacer

                observers.append(RealtimePacer(world, request.realtime))
            for node in self.tree.nodes():
                node.setup(cell=cell)

            # the judge reads contacts every tick only for goals judged by placement (~0.1 ms a tick otherwise
            # spent on a pick, `bt-grasp bench budget`); reading changes nothing in the world
            observe = judge.observe if judge.places(self.inputs.goal) else None

            def tick_hook(tick: int, tree: LoadedTree) -> None:
                ticked[0] = tick
                if observe is not None:
                    observe()
                if injector is not None:
                    injector.after_tick(tick)
                for callback in (*observers, *on_tick):
                    callback(tick, tree)

            if injector is not None:
                injector.before_run()
            tick_recorder: TickRecorder | None = recorder
            read_robot = _when_watched(recorder, robot_state_reader(cell))
            printer = None
            if request.fingerprint:
                from bt_grasp.recording.fingerprint import FingerprintRecorder

                printer = FingerprintRecorder()
                tick_recorder = printer if recorder is None else _Both(recorder, printer)
                read_robot = robot_state_reader(cell)  # every tick, watched or not
            if controller is not None:
                controller.attach(self.tree, world.now_ns, sink=recorder,
                                  fire_fault=None if injector is None else _fault_firer(injector))
            runner = TreeRunner(self.tree, world, steps_per_tick=world.steps_per_tick, recorder=tick_recorder,
                                robot_state=read_robot, on_tick=tick_hook, gate=controller,
                                on_failure=self._failure_seen if self.on_failure else None)
            try:
                outcome = runner.run(request.max_ticks)
            except KeyboardInterrupt:  # Ctrl-C: the log is finished and says the run was interrupted, not ended
                if recorder is not None:
                    recorder.write_result(world.now_ns(), interrupted_result(ticked[0], world.now_ns(), request.seed))
                raise
            unfinished = cell.attempts.finish(outcome.ticks)  # an attempt still going when the run ended
            if unfinished is not None:
                cell.media.attempt(unfinished)
            # a placement goal's "resting for 1 s after release" needs the world to run on a little
            for _ in range(judge.settle_ticks(self.inputs.goal)):
                world.step_tick()
                judge.observe()
            verdict = judge.check(self.inputs.goal)
            last = outcome.last_failure
            success = verdict.success and outcome.status == "SUCCESS"
            reason = None
            # the tree succeeded and the goal did not: the goal's first unmet condition is why, not a leaf's
            # failure the tree recovered from (a leaf's reason only when the tree failed)
            goal_not_met = not success and outcome.status == "SUCCESS"
            if not success:
                reason = last.reason if last else ("MAX_TICKS" if outcome.status == "RUNNING" else None)
                if goal_not_met:
                    reason = GOAL_NOT_MET
                if outcome.stopped:
                    reason = "STOPPED"  # an operator ended the run (bt_grasp.control)
            blamed = None if success or goal_not_met else last
            result = EpisodeResult(
                success=success,
                tree_status=outcome.status,
                reason=reason,
                failed_leaf=blamed.leaf if blamed else None,
                failed_path=blamed.path if blamed else None,
                failure_chain=tuple(ChainStep(e.tick, e.stamp_ns * 1e-9, e.path, e.reason, e.followed)
                                    for e in outcome.chain),
                ticks=outcome.ticks,
                sim_time_s=outcome.sim_time_s,
                wall_time_s=outcome.wall_time_s,
                retries=outcome.retries,
                judged=judged(verdict, judge.object_poses()),
                also_judged=tuple(judged(judge.check(g)) for g in request.also_judge),
                log=str(request.log) if request.log else None,
                seed=request.seed,
                faults_fired=injector.fired if injector is not None else 0,
                faults=injector.report() if injector is not None else (),
                goal=self.inputs.goal,
                planning=self.planning.stats(),
            )
            if printer is not None:
                result = replace(result, fingerprint=printer.finish(result.judged.object_poses).digest)
            if recorder is not None:
                if extras is not None:
                    extras.finish()
                recorder.write_result(world.now_ns(), _logged_result(result.to_json(), request.log_epoch_ns))
        finally:
            if controller is not None:
                controller.finish(ticked[0])  # the view's last tick: the result's
            if injector is not None:
                injector.close()  # a reused world starts the next episode as built
            if recorder is not None:
                _close_log(recorder, request.log)
            if self.live is not None:
                self.live.close()
        return result

    def _assemble(self, recorder: RunRecorder | None, controller: Controller | None) -> Cell:
        """The run's cell (``bt_grasp.episode.cell_assembly``): faults installed when a plan is given or an
        operator may fire them (with no plan nothing changes until one is fired by hand)."""
        from bt_grasp.episode.cell_assembly import FaultSetting, assemble_cell

        faults = None
        if self.inputs.fault_plan is not None or controller is not None:
            from bt_grasp.faults.plan import FaultPlan

            faults = FaultSetting(self.inputs.fault_plan or FaultPlan(()), self.tree, self.physics,
                                  self.fault_seed_sequence)
        assembled = assemble_cell(self.devices, self.scene, self.request.seed, self.inputs.calibration,
                                  recorder=recorder, now_ns=self.world.now_ns, faults=faults)
        self.cell, self.planning, self._injector = assembled.cell, assembled.planning, assembled.injector
        return assembled.cell

    @property
    def physics(self) -> PhysicsHook:
        """The simulator's hook for physical faults (pushes, a weakened grip)."""
        from bt_grasp.sim.disturbances import SimDisturbances

        return SimDisturbances(self.world)

    @property
    def fault_seed_sequence(self) -> np.random.SeedSequence:
        return self.world.fault_seed_sequence

    def _open_recorder(self) -> RunRecorder | None:
        request = self.request
        if request.log is None and request.live_port is None:
            return None
        from bt_grasp.episode.metadata import run_attachments, run_metadata
        from bt_grasp.foxglove.tree_layout import LAYOUT_ATTACHMENT, layout_bytes
        from bt_grasp.recording import topics
        from bt_grasp.recording.robot_model import default_robot_model
        from bt_grasp.recording.scene_entities import fixture_update
        from bt_grasp.recording.writer import BASE_FRAME, WORLD_FRAME, RunRecorder
        from bt_grasp.tree.introspect import node_records, tree_structure

        if request.live_port is not None:  # first: a port that cannot be bound leaves no log behind
            from bt_grasp.foxglove.live import LiveServer

            self.live = LiveServer(request.live_port, request.live_host)
        if request.log is not None:
            request.log.parent.mkdir(parents=True, exist_ok=True)
        recorder = RunRecorder(
            request.log,
            metadata=run_metadata(
                request, self.scene, self.tree, self.inputs.calibration_path, self.inputs.goal
            ),
            attachments={**run_attachments(request, self.tree, self.inputs.calibration_path),
                         # the Foxglove layout of this tree (its leaves' rows, by path)
                         LAYOUT_ATTACHMENT: layout_bytes(tree_structure(self.tree.root), request.tree.name)},
            flush_every_ticks=LOG_FLUSH_EVERY_TICKS,
            wall_clock=_wall_clock(request.log_epoch_ns),
            time_origin_ns=request.log_epoch_ns,  # None: now
            robot_model=default_robot_model(),
            leaf_names=[n["path"] for n in node_records(self.tree.root) if n["kind"] in ("Action", "Condition")],
            writer_process=True,  # a file log is written by a child process; the tick loop only hands over
        )
        # the frame tree's root: where the robot is bolted (installation data), repeated with every /tf
        recorder.static_transforms[(WORLD_FRAME, BASE_FRAME)] = self.scene.T_world_base()
        if self.live is not None:
            self.live.attach(recorder)
            for callback in self.on_live:
                callback(self.live.url)
        recorder.write_scene(topics.ROBOT_MODEL, 0, recorder.robot_model_update())
        recorder.write_scene(topics.SCENE, 0, fixture_update(self.scene, recorder.t(0)))
        recorder.write_tree_structure(self.world.now_ns(), tree_structure(self.tree.root))
        return recorder


def _wall_clock(epoch_ns: int | None) -> Callable[[], int]:
    """The recorder's wall clock: the real one, or a log's fixed time origin (``SOURCE_DATE_EPOCH``)."""
    if epoch_ns is None:
        return time.time_ns
    return lambda: epoch_ns


def _logged_result(result: Mapping[str, object], epoch_ns: int | None) -> Mapping[str, object]:
    """The /run/result a log holds: without wall-clock figures when its time origin is fixed."""
    if epoch_ns is None:
        return result
    from bt_grasp.recording.reproducible import without_wall_clock

    return without_wall_clock(result)


def _close_log(recorder: RunRecorder, path: Path | None) -> None:
    """Finish the log; a write that fails now (a full disk, the file's folder gone) is one sentence naming the
    file, not the writer's traceback."""
    from bt_grasp.recording.writer_process import WriterProcessError

    in_flight = sys.exc_info()[1]  # called from a ``finally``: an exception already on its way wins
    try:
        recorder.close()
    except (OSError, WriterProcessError) as exc:
        if in_flight is not None:
            log.warning("the log %s was not finished: %s", path, exc)
            return
        why = str(exc).split(": ")[-1] if isinstance(exc, WriterProcessError) else (exc.strerror or str(exc))
        why = re.sub(r"^\[Errno \d+\] ", "", why).lower()
        raise InputError("--log", f"cannot finish writing '{path}': {why}") from None


def goal_entries(goal: Goal) -> dict[str, BlackboardValue]:
    """What a goal tells trees that read ``{color}`` and ``{lift_height}`` (a pick), or ``{count}`` (a collect) (the
    request's blackboard wins)."""
    if isinstance(goal, PickGoal):
        return {"color": goal.color or "", "lift_height": goal.height_m}
    if isinstance(goal, CollectGoal):
        return {"count": goal.count}
    return {}


def judged(verdict: Verdict, object_poses: dict[str, list[list[float]]] | None = None) -> Judged:
    failed = verdict.failed
    return Judged(
        goal=verdict.goal,
        success=verdict.success,
        failed_condition=failed.criterion.value if failed is not None else None,
        conditions=tuple((c.criterion.value, c.met, c.detail) for c in verdict.conditions),
        object_name=verdict.object_name,
        object_lift_m=verdict.object_lift_m,
        in_gripper=verdict.in_gripper,
        lifted_objects=verdict.lifted_objects,
        objects_in_workspace=verdict.objects_in_workspace,
        object_poses=dict(object_poses or {}),
    )


RobotState = dict[str, list[float] | list[list[float]] | float]


def robot_state_reader(cell: Cell) -> Callable[[], RobotState]:
    """What the log records of the robot every tick: measured joints and gripper (the recorder computes every
    link's pose, the tool's among them, from these with one forward kinematics)."""

    def read() -> RobotState:
        return {
            "q_rad": cell.robot.joint_positions().tolist(),
            "qd_rad_s": cell.robot.joint_velocities().tolist(),
            "gripper_width_m": cell.robot.gripper_width_m(),
        }

    return read


class _Both:
    """A TickRecorder that hands every tick to the log's recorder and to the fingerprint."""

    def __init__(self, first: TickRecorder, second: TickRecorder) -> None:
        self.first, self.second = first, second

    def write_tick(self, tick: int, stamp_ns: int, nodes: Sequence[NodeRecord], blackboard: Mapping[str, object],
                   robot: Mapping[str, object] | None = None) -> None:
        self.first.write_tick(tick, stamp_ns, nodes, blackboard, robot)
        self.second.write_tick(tick, stamp_ns, nodes, blackboard, robot)

    def write_event(self, stamp_ns: int, kind: str, payload: Mapping[str, object]) -> None:
        self.first.write_event(stamp_ns, kind, payload)
        self.second.write_event(stamp_ns, kind, payload)

    def flush_tick(self) -> None:
        self.first.flush_tick()
        self.second.flush_tick()


def _when_watched(recorder: RunRecorder | None, read: Callable[[], RobotState]) -> Callable[[], RobotState]:
    """The arm state only when the recorder passes it on (a live view nobody watches reads nothing)."""
    if recorder is None or recorder.to_file:
        return read
    return lambda: read() if recorder.active else {}


def _fault_firer(injector: Injector) -> FaultFirer:
    """An operator's FireFault, checked as a fault plan's fault and armed now."""
    from bt_grasp.control.commands import CommandError
    from bt_grasp.faults.plan import fault_now

    def fire(kind: str, params: Mapping[str, object], tick: int) -> str:
        try:
            fault = fault_now(kind, params, tick, "fault")
            injector.fire_now(fault, tick)
        except InputError as exc:
            raise CommandError(exc.message) from None
        return f"{fault.label} armed"

    return fire


def run_episode(request: EpisodeRequest, *, worlds: WorldSource | None = None,
                on_tick: Sequence[TickCallback] = (), controller: Controller | None = None) -> EpisodeResult:
    """Prepare and run one episode (``worlds``: where the world comes from; default a fresh one;
    ``controller``: an interactive run, see :meth:`Episode.run`)."""
    return Episode(request, worlds).run(on_tick, controller)
