"""The URScript built-ins the control script calls, carried out by the twin's controller (``ScriptArm``).

The arm keeps one motion generator (:mod:`bt_grasp.sim.twin.motion`) at a time: a new command replaces the
running one, starting from the commanded joint state (a stop starts from the commanded speeds too). Poses are
UR poses in the controller's ``base`` frame of the current TCP (``set_tcp``); kinematics is
:class:`bt_grasp.sim.twin.kinematics.UrKinematics`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bt_grasp.sim.twin.kinematics import UrKinematics, pose_trans
from bt_grasp.sim.twin.motion import (
    Decelerate,
    Hold,
    JointMove,
    LinearMove,
    Motion,
    MotionError,
    ServoMove,
    SpeedMove,
    T_to_pose,
    pose_to_T,
)

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]
#: a joint speed below this (rad/s) on every joint is "steady" (URScript's is_steady)
STEADY_RAD_S = 0.005


def finite(values: object, what: str) -> Vec:
    """``values`` as floats, or MotionError naming ``what`` (a client's registers may hold NaN or infinity)."""
    array = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(array)):
        raise MotionError(f"{what}: {np.round(array, 6).tolist()} is not a finite number")
    return array


def positive(value: float, what: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise MotionError(f"{what} must be a positive number, got {value!r}")
    return float(value)


class Handle:
    """A motion the program waits for: done when it finished or another motion replaced it."""

    def __init__(self, arm: TwinArm, motion: Motion) -> None:
        self._arm = arm
        self.motion = motion

    @property
    def done(self) -> bool:
        return self.motion.done or self._arm.motion is not self.motion


class TwinArm:
    def __init__(self, kin: UrKinematics, q_start: Vec, T_flange_tcp: NDArray[np.float64],
                 actual: Callable[[], tuple[Vec, Vec]], on_protective_stop: Callable[[str], None],
                 on_watchdog: Callable[[str, float], None]) -> None:
        self.kin = kin
        self.motion: Motion = Hold(q_start)
        self.T_flange_tcp = np.array(T_flange_tcp, dtype=float)
        self.payload_kg = 0.0
        self.payload_cog_m = np.zeros(3)
        self._actual = actual
        self._on_protective_stop = on_protective_stop
        self._on_watchdog = on_watchdog

    # --- the controller's side --------------------------------------------------------------------------
    @property
    def q_cmd(self) -> Vec:
        return self.motion.q

    @property
    def qd_cmd(self) -> Vec:
        return self.motion.qd

    def advance(self, dt: float, speed_fraction: float) -> tuple[Vec, Vec]:
        """The commanded joint state after ``dt`` (the speed slider stretches a movej/movel's time)."""
        if self.motion.scaled:
            q, qd = self.motion.advance(dt * speed_fraction)
            return q, qd * speed_fraction
        return self.motion.advance(dt)

    def halt(self, decel_rad_s2: float, from_actual: bool = False) -> None:
        """Stop from the commanded joint state (a program stop), or from the measured one (a protective stop:
        the robot stops where it is, not where it was told to be, e.g. pressed into what it hit)."""
        q, qd = self._actual() if from_actual else (self.motion.q, self.motion.qd)
        self.motion = Decelerate.joint(q, qd, decel_rad_s2)

    def hold_actual(self) -> None:
        """Hold where the joints are (power off, brakes)."""
        self.motion = Hold(self._actual()[0])

    # --- ScriptArm --------------------------------------------------------------------------------------
    def _start(self, motion: Motion) -> Handle:
        self.motion = motion
        return Handle(self, motion)

    def _check_joints(self, q: Vec, what: str) -> Vec:
        q = np.asarray(q, dtype=float)
        if not self.kin.within_limits(q):
            raise MotionError(f"{what}: the target {np.round(q, 4).tolist()} is beyond the joint limits")
        return q

    def movej(self, q: Vec, accel: float, speed: float) -> Handle:
        return self._start(JointMove(self.motion.q, self._check_joints(q, "movej"), speed, accel))

    def _ik(self, T: NDArray[np.float64], q_near: Vec) -> Vec | None:
        return self.kin.ik(T, self.T_flange_tcp, q_near)

    def movel(self, pose: Vec, accel: float, speed: float) -> Handle:
        pose = finite(pose, "movel's pose")
        q0 = self.motion.q
        T0 = self.kin.T_base_tcp(q0, self.T_flange_tcp)
        return self._start(LinearMove(q0, T0, pose_to_T(pose), speed, accel, self._ik))

    def movel_to_joints(self, q: Vec, accel: float, speed: float) -> Handle:
        q = self._check_joints(q, "movel")
        return self.movel(self.kin.tcp_pose(q, self.T_flange_tcp), accel, speed)

    def servoj(self, q: Vec, servo_time_s: float) -> None:
        q = self._check_joints(q, "servoj")
        servo_time_s = positive(servo_time_s, "servoj's time")
        if not isinstance(self.motion, ServoMove):
            self.motion = ServoMove(self.motion.q)
        self.motion.retarget(q, servo_time_s)

    def speedj(self, qd: Vec, accel: float) -> None:
        qd, accel = finite(qd, "speedj's joint speeds"), positive(accel, "speedj's acceleration")
        if not isinstance(self.motion, SpeedMove):
            self.motion = SpeedMove(self.motion.q, self.motion.qd)
        self.motion.retarget(qd, accel)

    def stopj(self, decel: float) -> Handle:
        return self._start(Decelerate.joint(self.motion.q, self.motion.qd, positive(decel, "stopj's deceleration")))

    def stopl(self, decel: float) -> Handle:
        """``stopl(a)``: the tool's speed falls at ``a`` m/s^2 (the joints slow together to match)."""
        decel = positive(decel, "stopl's deceleration")
        q, qd = self.motion.q, self.motion.qd
        h = 1e-3
        v_tcp = np.linalg.norm(self.kin.T_base_tcp(q + qd * h, self.T_flange_tcp)[:3, 3]
                               - self.kin.T_base_tcp(q, self.T_flange_tcp)[:3, 3]) / h
        return self._start(Decelerate(q, qd, float(v_tcp) / max(decel, 1e-6)))

    def protective_stop(self, reason: str) -> None:
        self._on_protective_stop(reason)

    def set_tcp(self, pose: Vec) -> None:
        self.T_flange_tcp = pose_to_T(finite(pose, "set_tcp's pose"))
        log.info("TCP set to %s", np.round(np.asarray(pose, dtype=float), 5).tolist())

    def tcp_offset(self) -> Vec:
        return T_to_pose(self.T_flange_tcp)

    def set_payload(self, mass_kg: float, cog_m: Vec) -> None:
        self.payload_kg = float(finite(mass_kg, "set_payload's mass"))
        self.payload_cog_m = finite(cog_m, "set_payload's centre of gravity")

    def inverse_kin(self, pose: Vec, q_near: Vec | None) -> Vec | None:
        near = self._actual()[0] if q_near is None else finite(q_near, "get_inverse_kin's qnear")
        return self.kin.ik_pose(finite(pose, "get_inverse_kin's pose"), self.T_flange_tcp, near)

    def forward_kin(self, q: Vec | None, tcp: Vec | None) -> Vec:
        joints = self._actual()[0] if q is None else finite(q, "get_forward_kin's joints")
        T_tcp = self.T_flange_tcp if tcp is None else pose_to_T(finite(tcp, "get_forward_kin's TCP"))
        return self.kin.tcp_pose(joints, T_tcp)

    def pose_trans(self, p_from: Vec, p_from_to: Vec) -> Vec:
        return pose_trans(finite(p_from, "pose_trans"), finite(p_from_to, "pose_trans"))

    def flange_pose(self) -> Vec:
        return T_to_pose(self.kin.T_base_flange(self._actual()[0]))

    def is_steady(self) -> bool:
        return bool(np.all(np.abs(self._actual()[1]) < STEADY_RAD_S))

    def joints_within_limits(self, q: Vec) -> bool:
        return self.kin.within_limits(q)

    def pose_within_limits(self, pose: Vec) -> bool:
        return self.inverse_kin(pose, None) is not None

    def set_watchdog(self, register_name: str, min_frequency_hz: float) -> None:
        self._on_watchdog(register_name, min_frequency_hz)
