"""Building and running one task run: validate every input, build the cell, tick, judge, summarise.

This is the composition root of ``bt-grasp run`` (and of ``demo`` and ``replay --resim``): the only place
where the simulator, the pipeline services, the tree and the recorder meet.
"""

from __future__ import annotations

import json
import logging
import subprocess
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from bt_grasp.errors import InputError

log = logging.getLogger(__name__)

DEFAULT_MAX_TICKS = 12000  # 120 s of simulated time at 100 Hz
#: the log is flushed at the first tick boundary after this much wall time: a killed run loses at most this
LOG_FLUSH_INTERVAL_S = 0.05


@dataclass(frozen=True)
class RunRequest:
    tree: Path
    scene: Path
    seed: int = 0
    calibration: Path | None = None
    log: Path | None = None
    max_ticks: int = DEFAULT_MAX_TICKS
    faults: Path | None = None
    inject: tuple[str, ...] = ()
    blackboard: Mapping[str, Any] = field(default_factory=dict)
    argv: tuple[str, ...] = ()


@dataclass
class RunSummary:
    success: bool
    tree_status: str
    reason: str | None
    failed_leaf: str | None
    ticks: int
    sim_time_s: float
    wall_time_s: float
    retries: dict[str, int]
    object_lift_m: float
    judge: dict[str, Any]
    log: str | None
    seed: int
    faults_fired: int = 0

    def to_json(self) -> dict[str, Any]:
        return {
            "success": self.success,
            "tree_status": self.tree_status,
            "reason": self.reason,
            "failed_leaf": self.failed_leaf,
            "ticks": self.ticks,
            "sim_time_s": round(self.sim_time_s, 3),
            "wall_time_s": round(self.wall_time_s, 3),
            "retries": self.retries,
            "object_lift_m": round(self.object_lift_m, 4),
            "judge": self.judge,
            "log": self.log,
            "seed": self.seed,
            "faults_fired": self.faults_fired,
        }


def _versions() -> str:
    out = []
    for name in ("bt-grasp", "sapien", "py-trees", "opencv-python-headless", "open3d", "pin", "ompl", "ruckig", "mcap"):
        try:
            out.append(f"{name}={version(name)}")
        except PackageNotFoundError:
            out.append(f"{name}=?")
    return " ".join(out)


def _git_commit() -> str:
    try:
        proc = subprocess.run(
            ["git", "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5, cwd=Path(__file__).parent
        )
        return proc.stdout.strip() if proc.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


class Prepared:
    """Every input validated and every object built, before the first tick (so bad input runs nothing)."""

    def __init__(self, request: RunRequest) -> None:
        from bt_grasp.behaviours import robot_registry
        from bt_grasp.scene_config import load_scene
        from bt_grasp.tree.loader import load_tree

        self.request = request
        self.scene = load_scene(request.scene)
        from bt_grasp.perception.calibration_file import calibration_for_scene

        # --calibration, else the file the scene names beside it; another mount or camera pose is bad input
        self.calibration_path, self.calibration = calibration_for_scene(
            self.scene, request.scene, request.calibration
        )
        self.fault_plan = None
        if request.faults is not None or request.inject:
            from bt_grasp.faults.plan import load_fault_plan

            self.fault_plan = load_fault_plan(request.faults, request.inject)
        from bt_grasp.sim.world import World

        self.world = World(self.scene, request.seed, source=request.scene)
        self.tree = load_tree(request.tree, robot_registry(), clock=self.world.clock)
        for key, value in request.blackboard.items():
            self.tree.root_blackboard.set(key, value)
        if self.calibration_path is not None:
            self.tree.root_blackboard.set("calibration_file", str(self.calibration_path))
        self.cell = build_cell(self)
        if any(node.bt_type == "Calibrate" for node in self.tree.nodes()):
            self.cell.extras = {"calibration_board": self._mount_board()}

    def _mount_board(self) -> tuple[Any, Any]:
        """Mount the ChArUco board for a tree that calibrates: on the gripper (eye-to-hand) or the table."""
        from bt_grasp.geometry import inv
        from bt_grasp.perception.charuco import BoardSpec
        from bt_grasp.sim.charuco import attach_board_to_link, place_board_on_table

        spec = BoardSpec()
        if self.scene.camera.mount == "eye-to-hand":
            return spec, attach_board_to_link(self.world, spec, "gripper_palm")
        return spec, inv(self.scene.T_world_base()) @ place_board_on_table(self.world, spec)

    def attachments(self) -> dict[str, bytes]:
        files: dict[str, bytes] = {}
        for name, text in self.tree.sources.items():
            files[f"tree/{Path(name).name}"] = text.encode()
        files[f"scene/{self.request.scene.name}"] = self.request.scene.read_bytes()
        if self.calibration_path is not None:
            files[f"calibration/{self.calibration_path.name}"] = self.calibration_path.read_bytes()
        if self.request.faults is not None:
            files[f"faults/{self.request.faults.name}"] = self.request.faults.read_bytes()
        return files

    def metadata(self) -> dict[str, str]:
        r = self.request
        return {
            "seed": str(r.seed),
            "tree_file": str(r.tree),
            "scene_file": str(r.scene),
            "calibration_file": str(self.calibration_path or ""),
            "fault_plan": str(r.faults or ""),
            "inject": ";".join(r.inject),
            "blackboard": json.dumps(dict(r.blackboard), sort_keys=True, default=str),
            "max_ticks": str(r.max_ticks),
            "command_line": " ".join(r.argv or sys.argv),
            "tick_rate_hz": str(self.scene.physics.control_rate_hz),
            "versions": _versions(),
            "git_commit": _git_commit(),
            "main_tree": self.tree.main_tree,
        }


def build_cell(prepared: Prepared) -> Any:
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.motion.executor import ExecutorOptions
    from bt_grasp.motion.kinematics import default_kinematics
    from bt_grasp.motion.planner import PlannerOptions, default_planner
    from bt_grasp.motion.trajectory import MotionLimits
    from bt_grasp.perception.config import PerceptionConfig
    from bt_grasp.perception.grasps import GraspSettings

    world = prepared.world
    services: dict[str, Any] = {
        "kinematics": default_kinematics(),
        "planner": default_planner(),
        "planner_options": PlannerOptions(seed=prepared.request.seed + 1, time_limit_s=2.0),
        "motion_limits": MotionLimits(),
        # a grasped object makes the wrist jitter by ~0.01 rad/s at rest: settle on position, not stillness
        "executor_options": ExecutorOptions(settle_velocity_rad_s=0.03),
        "perception_config": PerceptionConfig.for_scene(prepared.scene),
        "grasp_settings": GraspSettings(),
    }
    return Cell(
        robot=world.robot,
        camera=world.camera,
        clock=world.clock,
        scene=prepared.scene,
        seed=prepared.request.seed,
        services=services,
        calibration=prepared.calibration,
    )


def robot_state_reader(cell: Any) -> Callable[[], dict[str, Any]]:
    kin = cell.service("kinematics")

    def read() -> dict[str, Any]:
        q = cell.robot.joint_positions()
        return {
            "q_rad": q.tolist(),
            "qd_rad_s": cell.robot.joint_velocities().tolist(),
            "gripper_width_m": cell.robot.gripper_width_m(),
            "T_base_tcp": np.asarray(kin.fk(q)).tolist(),
        }

    return read


def execute(
    prepared: Prepared,
    on_tick: Callable[[int, Any], None] | None = None,
) -> tuple[RunSummary, list[dict[str, Any]]]:
    """Run the prepared tree to the end; returns the summary and the per-tick status stream."""
    from bt_grasp.sim.judge import Judge
    from bt_grasp.tree.runner import TreeRunner

    request, world, cell = prepared.request, prepared.world, prepared.cell
    judge = Judge(world)
    recorder = None
    if request.log is not None:
        from bt_grasp.cli.media import RecorderSink
        from bt_grasp.recording.writer import RunRecorder
        from bt_grasp.tree.introspect import tree_structure

        request.log.parent.mkdir(parents=True, exist_ok=True)
        recorder = RunRecorder(
            request.log,
            metadata=prepared.metadata(),
            attachments=prepared.attachments(),
            flush_interval_s=LOG_FLUSH_INTERVAL_S,
        )
        recorder.write_tree_structure(world.now_ns(), tree_structure(prepared.tree.root))
        cell.media = RecorderSink(recorder, world.now_ns)
    injector = None
    if prepared.fault_plan is not None:
        from bt_grasp.faults.injector import install_faults

        injector = install_faults(prepared.fault_plan, prepared, recorder)
    for node in prepared.tree.nodes():
        node.setup(cell=cell)

    def tick_hook(tick: int, tree: Any) -> None:
        if injector is not None:
            injector.after_tick(tick)
        if on_tick is not None:
            on_tick(tick, tree)

    if injector is not None:
        injector.before_run()
    runner = TreeRunner(
        prepared.tree,
        world,
        steps_per_tick=world.steps_per_tick,
        recorder=recorder,
        robot_state=robot_state_reader(cell),
        on_tick=tick_hook,
    )
    try:
        outcome = runner.run(request.max_ticks)
        lift = float(prepared.tree.root_blackboard.get("lift_height", 0.15) or 0.15)
        verdict = judge.judge(lift)
        last = outcome.last_failure
        task = task_kind(prepared.tree)
        left = judge.objects_in_workspace()
        if task == "pick":  # the object is held above the table by the lift height, in the gripper
            physics_ok = verdict.success
        elif task == "clear":  # nothing is left in the work area
            physics_ok = not left
        else:  # no physical goal to judge: the tree's own result
            physics_ok = True
        success = physics_ok and outcome.status == "SUCCESS"
        summary = RunSummary(
            success=success,
            tree_status=outcome.status,
            reason=None
            if success
            else (last.reason if last else ("MAX_TICKS" if outcome.status == "RUNNING" else None)),
            failed_leaf=None if success else (last.leaf if last else None),
            ticks=outcome.ticks,
            sim_time_s=outcome.sim_time_s,
            wall_time_s=outcome.wall_time_s,
            retries=outcome.retries,
            object_lift_m=verdict.object_lift_m,
            judge={
                "source": "simulator ground truth (judge only)",
                "object": verdict.object_name,
                "in_gripper": verdict.in_gripper,
                "lifted_objects": list(verdict.lifted_objects),
                "task": task,
                "success": physics_ok,
                "objects_in_workspace": list(left),
            },
            log=str(request.log) if request.log else None,
            seed=request.seed,
            faults_fired=injector.fired if injector is not None else 0,
        )
        if recorder is not None:
            recorder.write_result(world.now_ns(), summary.to_json())
    finally:
        if recorder is not None:
            recorder.close()
    return summary, runner.stream


def task_kind(tree: Any) -> str:
    """What the judge checks: "pick" (a tree that lifts), "clear" (one that sets objects aside), or "tree"."""
    types = {node.bt_type for node in tree.nodes()}
    if "MoveAbove" in types and "Lift" in types:
        return "clear"
    if "Lift" in types:
        return "pick"
    return "tree"


def parse_assignments(items: Sequence[str], source: str = "--set") -> dict[str, Any]:
    """KEY=VALUE pairs; values are parsed as YAML scalars (numbers, true/false) or kept as text."""
    import yaml

    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InputError(source, f"expected KEY=VALUE, got '{item}'")
        parsed = yaml.safe_load(value) if value else ""
        out[key] = parsed if isinstance(parsed, str | int | float | bool) else value
    return out
