"""A run on a real cell: the same tree files as on the simulator, on a UR through ur_rtde and a RealSense (or a twin
of both), on the wall clock, with safety before motion.

The composition beside the simulated one (``bt_grasp.episode.episode``): every input is read and checked first (the
tree against the cell's scene, the cell file, the calibration), then the devices are opened
(``bt_grasp.episode.cell_devices``: nothing moves there), the cell is assembled by
``bt_grasp.episode.cell_assembly`` from :class:`~bt_grasp.episode.cell_assembly.CellDevices` as a simulated run's is,
and the tree is ticked by the same :class:`~bt_grasp.tree.runner.TreeRunner` with the cell's wall-clock stepper
(``bt_grasp.hardware.wall_time``), one tick per controller period.

How a run ends:

* the tree ends, or ``max_ticks`` runs out: judged (below), the arm left where the tree left it;
* the cell ends it (a :class:`~bt_grasp.hardware.cell_faults.CellFault`: a protective or emergency stop, a program
  stopped from the pendant, a lost connection, a stall the watchdog ended, a silent gripper, a streamed target the
  guard refused): the arm is stopped, the tree halted, the run's reason is the fault's kind;
* Ctrl-C: ``stopJ``, the log finished with a result marked interrupted, and the interrupt goes on to the caller;
* any other exception: the arm is stopped on the way out.

Who judges: against a twin, the twin's physics judge (its control port: the same judge as a simulated run's) on the
run's goal, or the twin scene's own goal; on a robot nobody can know the truth: the run reports the tree's status and
its own checks (the gripper closed on something, the TCP's height over the table, the wrench the controller measures).
"""

from __future__ import annotations

import contextlib
import json
import logging
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from bt_grasp.defaults import DEFAULT_MAX_TICKS
from bt_grasp.episode.request import BlackboardValue
from bt_grasp.episode.result import ChainStep, EpisodeResult, Judged, interrupted_result
from bt_grasp.errors import InputError
from bt_grasp.files.json_types import JsonValue
from bt_grasp.scene.goals import Goal, PickGoal

if TYPE_CHECKING:
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.cell.format import Cell as CellFile
    from bt_grasp.episode.cell_devices import RealCell
    from bt_grasp.hardware.cell_faults import CellFault
    from bt_grasp.hardware.realsense_settings import RealSenseSettings
    from bt_grasp.perception.calibration_file import CalibrationFile
    from bt_grasp.recording.writer import RunRecorder
    from bt_grasp.scene.format import Scene
    from bt_grasp.tree.loader import LoadedTree
    from bt_grasp.tree.runner import FailureEvent, RunOutcome

log = logging.getLogger(__name__)

#: called before the arm's first motion with a sentence describing it; True lets it move (``--yes``: not asked)
Confirm = Callable[[str], bool]
#: called after every tick with the tick's number and the tree
TickCallback = Callable[[int, "LoadedTree"], None]

#: the log's chunk is handed to the OS every this many ticks (a killed run loses at most these)
LOG_FLUSH_EVERY_TICKS = 25
#: the gripper holds something when closed on a gap at least this wide (m)
HELD_MIN_M = 0.002


def _camera_settings() -> RealSenseSettings:
    # deferred: the hardware package's settings (no device library) only when a cell run is asked for
    from bt_grasp.hardware.realsense_settings import RealSenseSettings

    return RealSenseSettings()


@dataclass(frozen=True)
class CellRunRequest:
    """One run on a real cell: a tree file on a cell file. ``goal``: what the twin's judge checks (None: the twin
    scene's own goal; on a robot, nothing is judged); ``calibration``: instead of the cell file's; the rest as
    :class:`~bt_grasp.episode.request.EpisodeRequest`'s."""

    tree: Path
    cell: Path
    seed: int = 0
    goal: Goal | None = None
    calibration: Path | None = None
    log: Path | None = None
    max_ticks: int = DEFAULT_MAX_TICKS
    blackboard: Mapping[str, BlackboardValue] = field(default_factory=dict)
    argv: tuple[str, ...] = ()
    leaves: tuple[str, ...] = ()
    camera: RealSenseSettings = field(default_factory=_camera_settings)


@dataclass(frozen=True)
class CellRunResult:
    """How a cell run ended: the result every run has, and where it ran and what of the cell ended it."""

    result: EpisodeResult
    ran_on: str  # "twin" or "robot"
    address: str
    fault: str | None  # the cell fault's sentence, when the cell ended the run
    overruns: int  # control periods the tick loop was late for

    def to_json(self) -> dict[str, JsonValue]:
        return {**self.result.to_json(), "ran_on": self.ran_on, "address": self.address, "clock": "wall",
                "cell_fault": self.fault, "late_periods": self.overruns}


class _LateClock:
    """The tree's clock: the cell's wall clock once its devices are open (the tree is loaded and checked first)."""

    def __init__(self) -> None:
        self.clock: Any = None

    def now_ns(self) -> int:
        return 0 if self.clock is None else int(self.clock.now_ns())


@dataclass(frozen=True)
class CellInputs:
    cell: CellFile
    scene: Scene
    tree: LoadedTree
    calibration_path: Path | None
    calibration: CalibrationFile | None
    clock: _LateClock


def load_cell_inputs(request: CellRunRequest) -> CellInputs:
    """Read and check every input (InputError / ConfigError naming the file); nothing is opened."""
    from bt_grasp.behaviours import robot_registry
    from bt_grasp.behaviours.library import check_tree_against_scene
    from bt_grasp.cell.format import cell_file_path, load_cell
    from bt_grasp.episode.cell_scene import scene_for_cell
    from bt_grasp.perception.calibration_file import load_calibration
    from bt_grasp.tree.loader import load_tree

    cell = load_cell(request.cell)
    scene = scene_for_cell(cell)
    clock = _LateClock()
    tree = load_tree(request.tree, robot_registry(request.leaves), clock=clock)
    check_tree_against_scene(tree.nodes(), scene)
    path = request.calibration
    if path is None and cell.calibration is not None:
        path = cell_file_path(request.cell, cell.calibration)
        if not path.exists():
            raise InputError(request.cell, f"names the calibration file {cell.calibration}, which does not exist "
                             "(make it with `bt-grasp calibrate --cell`)")
    calibration = load_calibration(path, mount=cell.camera.mount) if path is not None else None
    if request.max_ticks < 1:
        raise InputError("--max-ticks", f"must be at least 1, got {request.max_ticks}")
    if request.log is not None:
        from bt_grasp.files.output_files import check_output_file

        check_output_file(request.log, "--log", example="run.mcap", inputs=(request.tree, request.cell, path))
    return CellInputs(cell, scene, tree, path, calibration, clock)


class CellEpisode:
    """A prepared cell run: inputs checked, nothing opened. ``run()`` once."""

    def __init__(self, request: CellRunRequest, confirm: Confirm | None) -> None:
        """``confirm``: asked before the arm's first motion (None: ``--yes``, not asked)."""
        self.request = request
        self.inputs = load_cell_inputs(request)
        self.confirm = confirm
        self.devices: RealCell | None = None
        self.cell: Cell | None = None
        #: called as it happens with every leaf FAILURE that is not by design
        self.on_failure: list[Callable[[FailureEvent], None]] = []
        self._ran = False

    def run(self, on_tick: Sequence[TickCallback] = ()) -> CellRunResult:
        from bt_grasp.episode.cell_devices import describe, open_cell
        from bt_grasp.hardware.cell_faults import CellFault

        if self._ran:
            raise RuntimeError("a CellEpisode runs once")
        self._ran = True
        inputs, request = self.inputs, self.request
        devices = self.devices = open_cell(inputs.cell, request.cell, request.camera)  # CellUnavailable: exit 2
        inputs.clock.clock = devices.clock
        where = describe(inputs.cell)
        recorder: RunRecorder | None = None
        ticked = [0]
        try:
            self._check_calibration(devices)
            devices.arm.confirm = self._confirm_first_motion
            recorder = self._open_recorder(devices, where)
            cell = self.cell = self._assemble(devices, recorder)
            entries = dict(request.blackboard)
            if where["ran_on"] == "twin" and request.goal is None:  # the twin's task, as a scene tells a simulated run
                entries = {**self._twin_goal_entries(), **{k: v for k, v in entries.items() if k != "lift_height"}}
            for key, value in entries.items():
                inputs.tree.root_blackboard.set(key, value)
            if inputs.calibration_path is not None:
                inputs.tree.root_blackboard.set("calibration_file", str(inputs.calibration_path))
            for node in inputs.tree.nodes():
                node.setup(cell=cell)
            outcome, fault = self._tick(devices, recorder, on_tick, ticked)
            result = self._result(devices, cell, outcome, fault, ticked[0], where)
            if recorder is not None:
                recorder.write_result(devices.clock.now_ns(), result.to_json())
            return result
        except KeyboardInterrupt:  # Ctrl-C: stopJ, then the log is finished and says the run was interrupted
            devices.arm.stop()
            if recorder is not None:
                now = devices.clock.now_ns()
                recorder.write_log(now, "WARN", "cell", "interrupted (Ctrl-C): stopJ sent")
                recorder.write_result(now, {**interrupted_result(ticked[0], now, request.seed), **where,
                                            "clock": "wall"})
            raise
        except CellFault as fault:  # outside the tick loop (confirming, assembling): nothing moved
            raise InputError(request.cell, f"the cell ended the run before it started: {fault}") from None
        finally:
            devices.close()
            if recorder is not None:
                from bt_grasp.episode.episode import _close_log

                _close_log(recorder, request.log)

    # -- the tick loop ---------------------------------------------------------------------------------------------
    def _tick(self, devices: RealCell, recorder: RunRecorder | None, on_tick: Sequence[TickCallback],
              ticked: list[int]) -> tuple[RunOutcome | None, CellFault | None]:
        from bt_grasp.episode.episode import robot_state_reader
        from bt_grasp.hardware.cell_faults import CellFault
        from bt_grasp.tree.runner import TreeRunner

        assert self.cell is not None
        camera_frame = _CameraFrame(recorder, self.cell) if recorder is not None else None

        def hook(tick: int, tree: LoadedTree) -> None:
            ticked[0] = tick
            if camera_frame is not None:
                camera_frame()
            for callback in on_tick:
                callback(tick, tree)

        runner = TreeRunner(self.inputs.tree, devices.stepper, steps_per_tick=1, recorder=recorder,
                            robot_state=robot_state_reader(self.cell), on_tick=hook,
                            on_failure=self._failure_seen if self.on_failure else None)
        devices.stepper.restart()
        try:
            devices.stepper.poll()  # the cell as it is before the first tick
            return runner.run(self.request.max_ticks), None
        except CellFault as fault:
            if recorder is not None:
                now = devices.clock.now_ns()
                recorder.write_event(now, "cell_fault", {"kind": fault.kind.value, "detail": fault.detail,
                                                         "tick": ticked[0]})
                recorder.write_log(now, "ERROR", "cell", str(fault))
            with contextlib.suppress(CellFault):
                self.inputs.tree.halt()  # cancel the leaves' motions (the arm takes no more commands)
            return None, fault

    def _failure_seen(self, event: FailureEvent) -> None:
        for callback in self.on_failure:
            callback(event)

    def _confirm_first_motion(self) -> bool:
        if self.confirm is None:
            return True
        arm = self.inputs.cell.arm
        return self.confirm(
            f"The arm at {arm.address} is about to make its first motion (caps: {arm.joint_speed_cap_rad_s:g} rad/s, "
            f"{arm.joint_accel_cap_rad_s2:g} rad/s^2, {arm.tool_speed_cap_m_s:g} m/s; the TCP stays in the workspace "
            "box). Is the cell clear and the emergency stop at hand?")

    # -- the result ---------------------------------------------------------------------------------------------------
    def _result(self, devices: RealCell, cell: Cell, outcome: RunOutcome | None, fault: CellFault | None,
                ticks: int, where: dict[str, str]) -> CellRunResult:
        now_s = devices.clock.now_ns() * 1e-9
        status = outcome.status if outcome is not None else "RUNNING"
        judged = (self._twin_verdict() if where["ran_on"] == "twin" else self._own_checks(devices, cell)) \
            if fault is None else _not_judged(self._goal(), "the cell ended the run before it could be judged")
        last = outcome.last_failure if outcome is not None else None
        tree_ok = status == "SUCCESS"
        success = tree_ok and judged.success and fault is None
        reason: str | None = None
        if fault is not None:
            reason = fault.kind.value
        elif not success:
            reason = last.reason if last else ("MAX_TICKS" if status == "RUNNING" else
                                               ("GOAL_NOT_MET" if tree_ok else None))
        chain = tuple(ChainStep(e.tick, e.stamp_ns * 1e-9, e.path, e.reason, e.followed)
                      for e in (outcome.chain if outcome is not None else ()))
        result = EpisodeResult(
            success=success, tree_status=status, reason=reason,
            failed_leaf=None if success or fault is not None else (last.leaf if last else None),
            failed_path=None if success or fault is not None else (last.path if last else None),
            failure_chain=chain, ticks=outcome.ticks if outcome is not None else ticks,
            sim_time_s=now_s, wall_time_s=outcome.wall_time_s if outcome is not None else now_s,
            retries=outcome.retries if outcome is not None else {}, judged=judged,
            log=str(self.request.log) if self.request.log else None, seed=self.request.seed, goal=judged.goal,
            planning=self._planning_stats(),
        )
        return CellRunResult(result, where["ran_on"], where["arm_address"],
                             None if fault is None else str(fault), devices.stepper.overruns)

    def _planning_stats(self) -> Any:
        return self._planning.stats()

    def _goal(self) -> Goal:
        if self.request.goal is not None:
            return self.request.goal
        color = self.request.blackboard.get("color")
        height = self.request.blackboard.get("lift_height")
        goal = PickGoal(kind="pick", color=str(color) if color else None)
        if isinstance(height, int | float) and not isinstance(height, bool) and height > 0:
            goal = goal.model_copy(update={"height_m": float(height)})
        return goal

    def _twin_goal_entries(self) -> dict[str, BlackboardValue]:
        """What the twin's task tells trees that read ``{color}`` and ``{lift_height}`` (the request's colour wins)."""
        from pydantic import TypeAdapter, ValidationError

        from bt_grasp.episode.episode import goal_entries
        from bt_grasp.hardware.twin_control import TwinControlError, twin_request

        try:
            reply = twin_request(self.inputs.cell.arm.address, "goal")
            goal: Goal = TypeAdapter(Goal).validate_python(reply.get("goal"))
        except (TwinControlError, ValidationError):
            log.warning("the twin did not say its goal; the tree's {color} and {lift_height} are the run's")
            return {}
        return goal_entries(goal)

    def _twin_verdict(self) -> Judged:
        """The twin's physics judge on the run's goal (or the twin scene's own)."""
        from pydantic import TypeAdapter, ValidationError

        from bt_grasp.hardware.twin_control import TwinControlError, twin_request

        goal = self.request.goal
        line = "judge" if goal is None else "judge " + json.dumps(goal.model_dump(mode="json"))
        try:
            reply = twin_request(self.inputs.cell.arm.address, line)
        except TwinControlError as exc:
            return _not_judged(self._goal(), f"the twin's judge could not be asked: {exc}")
        if not reply.get("ok"):
            return _not_judged(self._goal(), f"the twin's judge refused: {reply.get('error')}")
        try:
            judged_goal: Goal = TypeAdapter(Goal).validate_python(reply["goal"])
            conditions = tuple((str(c["criterion"]), bool(c["met"]), str(c["detail"])) for c in reply["conditions"])
        except (KeyError, TypeError, ValidationError):
            return _not_judged(self._goal(), "the twin's judge answered something that is not a verdict")
        failed = next((c for c, met, _ in conditions if not met), None)
        return Judged(goal=judged_goal, success=bool(reply.get("success")), failed_condition=failed,
                      conditions=conditions, object_name=reply.get("object") if isinstance(reply.get("object"), str)
                      else None, object_lift_m=float(reply.get("object_lift_m") or 0.0),
                      in_gripper=bool(reply.get("in_gripper")), source="the twin's physics judge")

    def _own_checks(self, devices: RealCell, cell: Cell) -> Judged:
        """On a robot: what the run can tell by itself (reported; the tree's status decides the run)."""
        arm = devices.arm
        width = arm.gripper_width_m()
        closed = arm.gripper_target_width_m() < 1e-6
        held = closed and width >= HELD_MIN_M
        q = arm.joint_positions()
        tcp_z = float(cell.kinematics.fk(q)[2, 3])
        height = tcp_z - self.inputs.cell.table_plane.height_m
        wrench = arm.tcp_wrench()
        wrench_text = "not reported" if wrench is None else f"{wrench[2]:+.1f} N along z"
        conditions = (
            ("held", held, f"the gripper is {'closed' if closed else 'open'} at {width * 1000:.1f} mm"),
            ("tcp_height", True, f"the TCP is {height:.3f} m above the table"),
            ("wrench", True, f"the controller measures {wrench_text} at the TCP"),
        )
        return Judged(goal=self._goal(), success=True, failed_condition=None, conditions=conditions,
                      in_gripper=held, source="the run's own checks (a real cell: no ground truth)")

    # -- set-up -----------------------------------------------------------------------------------------------------
    def _check_calibration(self, devices: RealCell) -> None:
        from bt_grasp.perception.calibration_file import intrinsics_problem

        calibration = self.inputs.calibration
        if calibration is None:
            return
        problem = intrinsics_problem(calibration, devices.camera.intrinsics)
        if problem is not None:
            raise InputError(self.inputs.calibration_path or "calibration", f"was not made with this cell's camera: "
                             f"{problem}")

    def _assemble(self, devices: RealCell, recorder: RunRecorder | None) -> Cell:
        from bt_grasp.episode.cell_assembly import CellDevices, RealCellServices, assemble_cell
        from bt_grasp.motion.trajectory import MotionLimits

        cell_file = self.inputs.cell
        limits = MotionLimits(max_velocity_rad_s=cell_file.arm.joint_speed_cap_rad_s,
                              max_acceleration_rad_s2=cell_file.arm.joint_accel_cap_rad_s2)
        real = RealCellServices(robot_urdf=devices.kinematics.urdf_path, guard=devices.guard,
                                motion_clock=devices.motion_clock, motion_limits=limits,
                                grasp_settings=grasp_settings_for(devices))
        board = board_mount(cell_file)
        assembled = assemble_cell(CellDevices(devices.arm, devices.camera, devices.clock, board, real=real,
                                              perception_latency_s=cell_file.camera.perception_latency_s),
                                  self.inputs.scene, self.request.seed, self.inputs.calibration, recorder=recorder)
        self._planning = assembled.planning
        return assembled.cell

    def _open_recorder(self, devices: RealCell, where: dict[str, str]) -> RunRecorder | None:
        request = self.request
        if request.log is None:
            return None
        from bt_grasp.cell.grippers import robot_urdf_with
        from bt_grasp.foxglove.tree_layout import LAYOUT_ATTACHMENT, layout_bytes
        from bt_grasp.recording import topics
        from bt_grasp.recording.robot_model import RobotModel
        from bt_grasp.recording.scene_entities import fixture_update
        from bt_grasp.recording.writer import BASE_FRAME, WORLD_FRAME, RunRecorder
        from bt_grasp.tree.introspect import node_records, tree_structure

        tree = self.inputs.tree
        request.log.parent.mkdir(parents=True, exist_ok=True)
        recorder = RunRecorder(
            request.log,
            metadata=self._metadata(where),
            attachments={**self._attachments(), LAYOUT_ATTACHMENT: layout_bytes(tree_structure(tree.root),
                                                                                request.tree.name)},
            flush_every_ticks=LOG_FLUSH_EVERY_TICKS,
            time_origin_ns=time.time_ns() - devices.clock.now_ns(),  # the log's time: the wall clock, as it ran
            robot_model=RobotModel(robot_urdf_with(devices.gripper_model.name)),
            leaf_names=[n["path"] for n in node_records(tree.root) if n["kind"] in ("Action", "Condition")],
            handle_signals=False,  # Ctrl-C is this run's to handle: stopJ first, then the log
        )
        recorder.static_transforms[(WORLD_FRAME, BASE_FRAME)] = self.inputs.scene.T_world_base()
        recorder.write_scene(topics.ROBOT_MODEL, 0, recorder.robot_model_update())
        recorder.write_scene(topics.SCENE, 0, fixture_update(self.inputs.scene, recorder.t(0)))
        recorder.write_tree_structure(0, tree_structure(tree.root))
        recorder.write_log(0, "INFO", "cell", f"a run on the {where['ran_on']} at {where['arm_address']}: wall-clock "
                           "time (the log's times are the run's start plus wall time)")
        return recorder

    def _metadata(self, where: dict[str, str]) -> dict[str, str]:
        from bt_grasp.episode.metadata import git_commit
        from bt_grasp.process.environment import versions_line

        r = self.request
        return {
            "seed": str(r.seed),
            "tree_file": str(r.tree),
            "scene_file": "",
            "cell_file": str(r.cell),
            "calibration_file": str(self.inputs.calibration_path or ""),
            "fault_plan": "",
            "inject": "",
            "blackboard": json.dumps(dict(r.blackboard), sort_keys=True, default=str),
            "goal": json.dumps(r.goal.model_dump(mode="json"), sort_keys=True) if r.goal is not None else "",
            "max_ticks": str(r.max_ticks),
            "command_line": " ".join(r.argv or sys.argv),
            "tick_rate_hz": str(self.inputs.cell.arm.control_rate_hz),
            "versions": versions_line(),
            "git_commit": git_commit(),
            "main_tree": self.inputs.tree.main_tree,
            "leaves": ";".join(r.leaves),
            "clock": "wall",
            **where,
        }

    def _attachments(self) -> dict[str, bytes]:
        files = {f"tree/{Path(name).name}": text.encode() for name, text in self.inputs.tree.sources.items()}
        files[f"cell/{self.request.cell.name}"] = self.request.cell.read_bytes()
        if self.inputs.calibration_path is not None:
            files[f"calibration/{self.inputs.calibration_path.name}"] = self.inputs.calibration_path.read_bytes()
        return files


def grasp_settings_for(devices: RealCell) -> Any:
    """Grasp synthesis for the cell's gripper: its stroke, its pads, its finger tips and palm."""
    from bt_grasp.perception.config import GraspSettings

    g = devices.cell.gripper
    return GraspSettings(max_opening_m=g.stroke_m, tcp_to_fingertip_m=g.tcp_to_fingertip_m,
                         pad_depth_m=g.pad_size_m[0], pad_thickness_m=g.pad_size_m[1],
                         palm_above_tcp_m=devices.gripper_model.palm_above_tcp_m)


def board_mount(cell: CellFile) -> Any:
    """The cell's calibration board as the calibration procedure knows it (None: none mounted)."""
    if cell.board is None:
        return None
    from bt_grasp.cell.format import pose_to_T
    from bt_grasp.perception.calibration import BoardMount
    from bt_grasp.perception.charuco import BoardSpec

    b = cell.board
    spec = BoardSpec(dictionary=b.dictionary, squares_x=b.squares_x, squares_y=b.squares_y, square_m=b.square_m,
                     marker_m=b.marker_m)
    return BoardMount(spec, pose_to_T(b.pose))


def _not_judged(goal: Goal, why: str) -> Judged:
    return Judged(goal=goal, success=False, failed_condition="not_judged", conditions=(("not_judged", False, why),),
                  source="nobody: " + why)


class _CameraFrame:
    """Keeps the log's base -> camera transform on the calibration the run holds (eye-in-hand: on the tool)."""

    def __init__(self, recorder: RunRecorder, cell: Cell) -> None:
        self.recorder = recorder
        self.cell = cell
        self._from: object = None

    def __call__(self) -> None:
        from bt_grasp.interfaces import Mount
        from bt_grasp.recording.writer import BASE_FRAME, CAMERA_FRAME

        calibration = self.cell.calibration
        if calibration is None or (calibration is self._from and calibration.mount != Mount.EYE_IN_HAND):
            return
        self._from = calibration
        T_base_tool = None
        if calibration.mount == Mount.EYE_IN_HAND:
            T_base_tool = self.cell.kinematics.fk_link(self.cell.robot.joint_positions(), calibration.tool_link)
        self.recorder.static_transforms[(BASE_FRAME, CAMERA_FRAME)] = np.asarray(
            calibration.T_base_camera_at(T_base_tool), dtype=np.float64)


def run_on_cell(request: CellRunRequest, confirm: Confirm | None, on_tick: Sequence[TickCallback] = ()
                ) -> CellRunResult:
    """Prepare and run one cell run (``confirm``: see :class:`CellEpisode`)."""
    return CellEpisode(request, confirm).run(on_tick)
