"""``bt-grasp calibrate`` below the command line: the Calibrate leaf's procedure, ticked in the simulator.

The same :class:`bt_grasp.behaviours.calibration_job.CalibrationJob` the ``Calibrate`` leaf runs, on the
same cell (``make_cell``, the board mounted by ``bt_grasp.sim.charuco.mount_calibration_board``), ticked at
the control rate with the world stepped between ticks exactly as a tree runner does: the same seed gives the
same calibration through either. Because this is a simulator, the result is then judged against the true
camera pose (labelled as such; never used to produce the calibration).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.geometry import Mat4
from bt_grasp.perception.calibration import CalibrationRun
from bt_grasp.scene.format import Scene, load_scene

if TYPE_CHECKING:
    from bt_grasp.behaviours.calibration_job import CalibrationJob
    from bt_grasp.sim.world import World

#: progress(visited, planned, note)
Progress = Callable[[int, int, str], None]

#: a calibration that has not finished after this much simulated time has failed
MAX_SIM_S = 600.0


@dataclass(frozen=True)
class SimCalibration:
    run: CalibrationRun
    T_true: Mat4  # true T_base_camera (eye-to-hand) or T_tool_camera (eye-in-hand): judge only
    true_error_per_method: dict[str, tuple[float, float]]  # mm, deg
    elapsed_s: float
    ticks: int


def calibrate_in_sim(scene: Path | Scene, mount: str, seed: int = 0, poses: int = 20,
                     progress: Progress | None = None) -> SimCalibration:
    """Build a world for ``mount`` with the board mounted, run the calibration procedure tick by tick,
    judge the result against ground truth. Raises ValueError when the calibration fails."""
    from bt_grasp.behaviours.calibration_job import CalibrationJob
    from bt_grasp.behaviours.cell import make_cell
    from bt_grasp.geometry import pose_error
    from bt_grasp.sim.charuco import mount_calibration_board
    from bt_grasp.sim.judge import true_camera_pose
    from bt_grasp.sim.world import World

    t0 = time.perf_counter()
    config = load_scene(scene) if isinstance(scene, Path) else scene
    world = World(config, seed, camera_mount=mount, source=scene if isinstance(scene, Path) else "scene")
    board = mount_calibration_board(world)
    cell = make_cell(world.robot, world.camera, world.clock, config, seed, board=board)
    run, ticks = tick_calibration(world, CalibrationJob(cell, poses), progress)
    outcome = run
    T_true = true_camera_pose(world, mount, outcome.calibration.tool_link)
    errors = {}
    for name, result in outcome.solution.per_method.items():
        dt, dr = pose_error(result.X, T_true)
        errors[name] = (dt * 1e3, float(np.degrees(dr)))
    return SimCalibration(outcome, T_true, errors, time.perf_counter() - t0, ticks)


def tick_calibration(world: World, job: CalibrationJob, progress: Progress | None = None
                     ) -> tuple[CalibrationRun, int]:
    """Tick ``job`` at the control rate, stepping the world between ticks as a tree runner does; returns the
    run and the number of ticks. Raises ValueError when it fails or runs out of simulated time."""
    max_ticks = int(MAX_SIM_S * world.config.physics.control_rate_hz)
    ticks, last = 1, ""
    outcome = job.update()
    while outcome is None and ticks < max_ticks:
        if progress is not None and job.progress != last:
            progress(job.visited, job.planned, job.progress)
            last = job.progress
        world.step(world.steps_per_tick)
        ticks += 1
        outcome = job.update()
    if outcome is None:
        job.cancel()
        raise ValueError(f"the calibration did not finish within {MAX_SIM_S:.0f} s of simulated time")
    if isinstance(outcome, str):
        raise ValueError(outcome)
    return outcome, ticks
