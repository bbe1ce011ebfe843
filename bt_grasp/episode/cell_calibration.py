"""``bt-grasp calibrate --cell``: hand-eye calibration on a real cell (or a twin), as the simulated run does it.

The same :class:`~bt_grasp.behaviours.calibration_job.CalibrationJob` the ``Calibrate`` leaf and ``bt-grasp calibrate
--scene`` run, on the cell's devices (``bt_grasp.episode.cell_devices``), assembled as a run's cell is (the board
from the cell file, the guard, the caps), ticked once a controller period by the cell's wall-clock stepper: views
planned from the camera's nominal mounting and the board's nominal pose on the gripper, the arm moved to each
(every motion checked before it is sent; views the guard refuses are skipped), the board seen, every hand-eye method
solved and the most consistent kept. The calibration file is written where the cell file says. Nothing here knows
where the camera really is: a test against a twin asks the twin's judge side for that.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.errors import BtGraspError, InputError

if TYPE_CHECKING:
    from bt_grasp.episode.cell_run import Confirm
    from bt_grasp.hardware.realsense_settings import RealSenseSettings
    from bt_grasp.perception.calibration import CalibrationRun

#: progress(visited, planned, note)
Progress = Callable[[int, int, str], None]
#: a calibration that has not finished after this much wall time has failed
MAX_WALL_S = 900.0


class CalibrationFailed(BtGraspError):
    """The calibration ran and did not succeed (too few views, a cell fault): one sentence, exit code 1."""


@dataclass(frozen=True)
class CellCalibration:
    run: CalibrationRun
    out: Path
    elapsed_s: float
    ticks: int
    ran_on: str
    address: str


def calibration_target(cell_path: Path) -> Path:
    """Where the cell file says its calibration file is (InputError when it names none)."""
    from bt_grasp.cell.format import cell_file_path, load_cell

    cell = load_cell(cell_path)
    if cell.calibration is None:
        raise InputError(cell_path, "names no calibration file (calibration: null): write the file's name there, "
                         "e.g. calibration: mycell.calibration.yaml")
    return cell_file_path(cell_path, cell.calibration)


def calibrate_cell(cell_path: Path, poses: int, seed: int, confirm: Confirm | None,
                   settings: RealSenseSettings | None = None, progress: Progress | None = None) -> CellCalibration:
    """Calibrate the cell's camera (see the module docstring); the file is written where the cell file says.
    Raises InputError when the cell cannot be calibrated (no board, a failed calibration), CellFault-derived
    InputError when the cell ended it."""
    from bt_grasp.behaviours.calibration_job import CalibrationJob
    from bt_grasp.cell.format import load_cell
    from bt_grasp.episode.cell_assembly import CellDevices, RealCellServices, assemble_cell
    from bt_grasp.episode.cell_devices import describe, open_cell
    from bt_grasp.episode.cell_run import board_mount, grasp_settings_for
    from bt_grasp.episode.cell_scene import scene_for_cell
    from bt_grasp.hardware.cell_faults import CellFault
    from bt_grasp.hardware.realsense_settings import RealSenseSettings
    from bt_grasp.motion.trajectory import MotionLimits
    from bt_grasp.perception.calibration_file import save_calibration

    cell_file = load_cell(cell_path)
    out = calibration_target(cell_path)
    board = board_mount(cell_file)
    if board is None:
        raise InputError(cell_path, "names no calibration board (board: null): screw the ChArUco board to the gripper "
                         "and describe it under board (docs/real-cell.md)")
    if cell_file.camera.mount != "eye-to-hand":
        raise InputError(cell_path, "calibrates an eye-to-hand camera only (the board on the gripper); a wrist camera "
                         "needs the board on the table, which a cell file cannot describe yet")
    scene = scene_for_cell(cell_file)
    start = time.monotonic()
    devices = open_cell(cell_file, cell_path, settings or RealSenseSettings())
    where = describe(cell_file)
    try:
        devices.arm.confirm = None if confirm is None else (lambda: confirm(
            f"The arm at {cell_file.arm.address} is about to move through {poses} calibration views with the board "
            "on the gripper. Is the cell clear and the emergency stop at hand?"))
        arm = cell_file.arm
        real = RealCellServices(robot_urdf=devices.kinematics.urdf_path, guard=devices.guard,
                                motion_clock=devices.motion_clock,
                                motion_limits=MotionLimits(max_velocity_rad_s=arm.joint_speed_cap_rad_s,
                                                           max_acceleration_rad_s2=arm.joint_accel_cap_rad_s2),
                                grasp_settings=grasp_settings_for(devices))
        cell = assemble_cell(CellDevices(devices.arm, devices.camera, devices.clock, board, real=real), scene, seed,
                             None).cell
        job = CalibrationJob(cell, poses)
        stepper = devices.stepper
        stepper.restart()
        ticks, last = 1, ""
        try:
            stepper.poll()
            outcome = job.update()
            while outcome is None and time.monotonic() - start < MAX_WALL_S:
                if progress is not None and job.progress != last:
                    progress(job.visited, job.planned, job.progress)
                    last = job.progress
                stepper.step()
                ticks += 1
                outcome = job.update()
        except CellFault as fault:
            raise CalibrationFailed(f"the cell ended the calibration ({fault}); the arm was stopped and nothing was "
                                    "written") from None
        if outcome is None:
            job.cancel()
            raise CalibrationFailed(f"the calibration did not finish within {MAX_WALL_S:.0f} s; nothing was written")
        if isinstance(outcome, str):
            raise CalibrationFailed(f"the calibration failed: {outcome}; nothing was written")
    except KeyboardInterrupt:
        devices.arm.stop()
        raise
    finally:
        devices.close()
    save_calibration(outcome.calibration, out)
    return CellCalibration(outcome, out, time.monotonic() - start, ticks, where["ran_on"], where["arm_address"])

