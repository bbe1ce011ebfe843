"""What each fault kind does when armed: one small function per kind, acting on the wrapped interfaces."""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bt_grasp.faults import physics
from bt_grasp.faults.armed import ArmedFault
from bt_grasp.faults.calibration import OffsetCalibration, offset_transform
from bt_grasp.faults.camera import FaultyCamera, depth_burst, depth_hole
from bt_grasp.faults.model import (
    CalibrationOffsetParams,
    ControllerStallParams,
    DepthBurstParams,
    DepthHoleParams,
    FaultKind,
    FrameDropParams,
    GripperSlipParams,
    LeafTimeoutParams,
    ObjectNudgeParams,
    PlannerFailParams,
    ServiceFailParams,
)
from bt_grasp.faults.physics import PhysicsHook
from bt_grasp.faults.robot import FaultyRobot
from bt_grasp.faults.services import FaultyKinematics, FaultyPlanner
from bt_grasp.faults.site import FaultableCell

log = logging.getLogger(__name__)


@dataclass
class Timer:
    """Runs ``action`` once the simulated clock reaches ``at_ns`` (checked after every tick)."""

    at_ns: int
    action: Callable[[], None]


@dataclass
class Wrapped:
    """The interfaces as the leaves see them once faults are installed, and the physics hook behind them."""

    cell: FaultableCell
    physics: PhysicsHook
    camera: FaultyCamera
    robot: FaultyRobot
    planner: FaultyPlanner
    kinematics: FaultyKinematics
    rngs: dict[int, np.random.Generator]  # per fault index in the plan
    timers: list[Timer] = field(default_factory=list)
    offsets: list[np.ndarray] = field(default_factory=list)
    color: str | None = None

    def now_ns(self) -> int:
        return int(self.cell.clock.now_ns())

    def apply_calibration_offsets(self) -> None:
        """Keep the summed offset on whatever calibration the cell holds (LoadCalibration may replace it)."""
        calibration = self.cell.calibration
        if not self.offsets or calibration is None:
            return
        total = np.eye(4)
        for T in self.offsets:
            total = T @ total
        if isinstance(calibration, OffsetCalibration):
            if np.allclose(calibration.T_offset, total):
                return
            calibration = calibration.inner
        self.cell.calibration = OffsetCalibration(calibration, total)


def _frame_drop(ep: ArmedFault, w: Wrapped, index: int) -> None:
    w.camera.add(ep, None, ep.params_as(FrameDropParams).frames)


def _depth_burst(ep: ArmedFault, w: Wrapped, index: int) -> None:
    p = ep.params_as(DepthBurstParams)
    w.camera.add(ep, depth_burst(p.sigma_m, p.fraction, w.rngs[index]), p.frames)


def _depth_hole(ep: ArmedFault, w: Wrapped, index: int) -> None:
    p = ep.params_as(DepthHoleParams)
    w.camera.add(ep, depth_hole(p.u_px, p.v_px, p.width_px, p.height_px), p.frames)


def _calibration_offset(ep: ArmedFault, w: Wrapped, index: int) -> None:
    p = ep.params_as(CalibrationOffsetParams)
    w.offsets.append(offset_transform((p.dx_mm, p.dy_mm, p.dz_mm), (p.droll_deg, p.dpitch_deg, p.dyaw_deg)))
    w.apply_calibration_offsets()
    ep.fire(effect="calibration offset", loaded=w.cell.calibration is not None)
    ep.finish()


def _ik_fail(ep: ArmedFault, w: Wrapped, index: int) -> None:
    w.kinematics.failing.add(ep, ep.params_as(ServiceFailParams).calls)


def _planner_fail(ep: ArmedFault, w: Wrapped, index: int) -> None:
    w.planner.failing.add(ep, ep.params_as(PlannerFailParams).calls)


def _controller_stall(ep: ArmedFault, w: Wrapped, index: int) -> None:
    w.robot.hold(ep, ep.params_as(ControllerStallParams).duration_s, gripper_too=False)


def _leaf_timeout(ep: ArmedFault, w: Wrapped, index: int) -> None:
    duration_s = ep.params_as(LeafTimeoutParams).duration_s
    until = w.now_ns() + round(duration_s * 1e9)
    w.robot.hold(ep, duration_s, gripper_too=True)
    w.camera.add(ep, None, None)
    ep.fire(effect="cell not responding", until_ns=until)


def _gripper_slip(ep: ArmedFault, w: Wrapped, index: int) -> None:
    p = ep.params_as(GripperSlipParams)
    details, restore = w.physics.weaken_grip(p.friction, p.force_n)
    ep.fire(effect="grip weakened", duration_s=p.duration_s, **details)

    def recover() -> None:
        restore()
        ep.finish()
        log.info("fault %s: pad friction restored", ep.fault.label)

    w.timers.append(Timer(w.now_ns() + round(p.duration_s * 1e9), recover))


def _object_nudge(ep: ArmedFault, w: Wrapped, index: int) -> None:
    p = ep.params_as(ObjectNudgeParams)
    name = physics.choose_object(w.physics, p.object, w.color)
    details = physics.push_object(w.physics, name, p.dx_m, p.dy_m)
    ep.fire(effect="object pushed", dx_m=p.dx_m, dy_m=p.dy_m, **details)
    ep.finish()


START: dict[FaultKind, Callable[[ArmedFault, Wrapped, int], None]] = {
    FaultKind.FRAME_DROP: _frame_drop,
    FaultKind.DEPTH_BURST: _depth_burst,
    FaultKind.DEPTH_HOLE: _depth_hole,
    FaultKind.CALIBRATION_OFFSET: _calibration_offset,
    FaultKind.IK_FAIL: _ik_fail,
    FaultKind.PLANNER_FAIL: _planner_fail,
    FaultKind.CONTROLLER_STALL: _controller_stall,
    FaultKind.LEAF_TIMEOUT: _leaf_timeout,
    FaultKind.GRIPPER_SLIP: _gripper_slip,
    FaultKind.OBJECT_NUDGE: _object_nudge,
}

#: kinds whose unused part may be dropped when the arming leaf's attempt ends (``within_attempt``)
SERVICE_KINDS = frozenset({FaultKind.IK_FAIL, FaultKind.PLANNER_FAIL})
