"""ur_rtde 1.6.5's control script, run by the twin: the register handshake, not the URScript.

One :meth:`ControlProgram.step` is one pass of the script's main loop (one controller cycle, the script's
``sync()``): read the command register; a real-time code is processed and answered "ready"; another code is
processed once and answered "done", and "ready" again once the client clears the register. A ``movej``/``movel``
that is not asynchronous holds the loop until the arm arrives, as the URScript call blocks; an asynchronous one
reports its progress in ``output_int_register_2`` as the script's ``write_async_progress_register`` does. Codes
outside :data:`bt_grasp.sim.twin.commands.SUPPORTED` stop the program with "unsupported by the twin: N".
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bt_grasp.sim.twin.commands import DONE_WITH_COMMAND, READY_FOR_COMMAND, REALTIME_CODES, SUPPORTED, Code
from bt_grasp.sim.twin.motion import MotionError

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]


class MoveHandle(Protocol):
    @property
    def done(self) -> bool: ...


class ScriptArm(Protocol):
    """The URScript built-ins the control script calls, as the twin's controller provides them."""

    def movej(self, q: Vec, accel: float, speed: float) -> MoveHandle: ...

    def movel(self, pose: Vec, accel: float, speed: float) -> MoveHandle: ...

    def movel_to_joints(self, q: Vec, accel: float, speed: float) -> MoveHandle: ...

    def servoj(self, q: Vec, servo_time_s: float) -> None: ...

    def speedj(self, qd: Vec, accel: float) -> None: ...

    def stopj(self, decel: float) -> MoveHandle: ...

    def stopl(self, decel: float) -> MoveHandle: ...

    def protective_stop(self, reason: str) -> None: ...

    def set_tcp(self, pose: Vec) -> None: ...

    def tcp_offset(self) -> Vec: ...

    def set_payload(self, mass_kg: float, cog_m: Vec) -> None: ...

    def inverse_kin(self, pose: Vec, q_near: Vec | None) -> Vec | None: ...

    def forward_kin(self, q: Vec | None, tcp: Vec | None) -> Vec: ...

    def pose_trans(self, p_from: Vec, p_from_to: Vec) -> Vec: ...

    def flange_pose(self) -> Vec: ...

    def is_steady(self) -> bool: ...

    def joints_within_limits(self, q: Vec) -> bool: ...

    def pose_within_limits(self, pose: Vec) -> bool: ...

    def set_watchdog(self, register_name: str, min_frequency_hz: float) -> None: ...


class _Finished:
    done = True


_FINISHED = _Finished()


class ProgramEnd(Exception):
    """The program stops (the script ended, failed, or met a code the twin does not run)."""


class ControlProgram:
    """The state of one running control script (the URScript globals the handshake needs)."""

    def __init__(self, arm: ScriptArm, register_offset: int, out_int: list[int], out_double: list[float]) -> None:
        self.arm = arm
        self.off = register_offset
        self.out_int = out_int
        self.out_double = out_double
        self.executing = False
        self.blocking: tuple[MoveHandle, Callable[[], MoveHandle]] | None = None
        self.async_move: MoveHandle | None = None
        self.async_stop: MoveHandle | None = None
        self.stop_type = 0  # the script's global: 0 stopj, 1 stopl (an asynchronous stop sets 1)
        self.servoing = False
        self.speeding = False
        self.async_wr_count = 0
        self.async_op_id = 0
        self._ints: Sequence[int] = ()
        self._doubles: Sequence[float] = ()
        self.write_async_progress(-1)  # reset_async_progress()
        self.signal(READY_FOR_COMMAND)

    # --- registers ------------------------------------------------------------------------------------
    def signal(self, value: int) -> None:
        self.out_int[0 + self.off] = value

    def reg_int(self, i: int) -> int:
        return int(self._ints[i + self.off])

    def reg_float(self, i: int) -> float:
        return float(self._doubles[i + self.off])

    def q_from(self, i: int) -> Vec:
        return np.array([self.reg_float(i + k) for k in range(6)])

    def to_floats(self, i: int, values: Vec) -> None:
        for k in range(6):
            self.out_double[i + k + self.off] = float(values[k])

    def write_async_progress(self, value: int) -> None:
        """The script's ``write_async_progress_register``: change count, operation id, running bit, progress."""
        self.async_wr_count = 0 if self.async_wr_count >= 127 else self.async_wr_count + 1
        if value == 0:
            self.async_op_id = 0 if self.async_op_id >= 127 else self.async_op_id + 1
        reg = self.async_wr_count * 65536 + self.async_op_id * 16777216
        if value >= 0:
            reg += min(value, 32767) + 32768
        self.out_int[2 + self.off] = reg

    # --- the main loop --------------------------------------------------------------------------------
    def step(self, ints: Sequence[int], doubles: Sequence[float]) -> None:
        """One pass of the main loop. Raises :class:`ProgramEnd` when the program stops."""
        self._ints, self._doubles = ints, doubles
        self._watch_async()
        if self.blocking is not None:
            if not self.blocking[0].done:
                return  # movej/movel still running: the loop is inside process_cmd
            self.blocking = None
            self.signal(DONE_WITH_COMMAND)  # process_cmd's tail
            return  # the loop's sync()
        cmd = self.reg_int(0)
        if cmd in REALTIME_CODES:
            self.process(cmd)
            self.signal(READY_FOR_COMMAND)
        elif cmd == Code.NO_CMD:
            self.executing = False
            self.signal(READY_FOR_COMMAND)
        else:
            if not self.executing:
                self.process(cmd)
            self.executing = True

    def resume(self) -> None:
        """Continue after a pause (the dashboard's ``play``): an interrupted ``movej``/``movel`` is issued again."""
        if self.blocking is not None and not self.blocking[0].done:
            self.blocking = (self.blocking[1](), self.blocking[1])

    def _watch_async(self) -> None:
        if self.async_move is not None and self.async_move.done:
            self.async_move = None
            self.write_async_progress(-1)  # move_thread's signal_async_operation_finished()
        if self.async_stop is not None and self.async_stop.done:
            self.async_stop = None
            self.write_async_progress(-1)

    def _stop_async_move(self) -> None:
        if self.async_move is not None:
            self.async_move = None  # "kill move_thrd"; the next motion replaces its trajectory
            self.write_async_progress(-1)

    def process(self, cmd: int) -> None:
        """``process_cmd(cmd)``: carry out one command; ends with "done" unless it blocks or stops the script."""
        if cmd not in SUPPORTED:
            raise ProgramEnd(f"unsupported by the twin: {cmd}")
        handler = _HANDLERS.get(Code(cmd))
        try:
            if handler is not None:
                handler(self)
        except (MotionError, ValueError) as exc:  # URScript's runtime errors: the program stops, not the controller
            raise ProgramEnd(f"the program stopped on command {cmd}: {exc}") from exc
        if cmd == Code.STOP_SCRIPT:
            raise ProgramEnd("the client stopped the control script (stopScript)")
        if self.blocking is None:
            self.signal(DONE_WITH_COMMAND)

    # --- commands -------------------------------------------------------------------------------------
    def _move(self, start: Callable[[], MoveHandle]) -> None:
        self._stop_async_move()
        if self.reg_int(1) == 1:
            self.async_move = start()
            self.write_async_progress(0)  # move_thread's signal_async_operation_started()
        else:
            self.blocking = (start(), start)

    def movej(self) -> None:
        q, v, a = self.q_from(0), self.reg_float(6), self.reg_float(7)
        self._move(lambda: self.arm.movej(q, a, v))

    def movej_ik(self) -> None:
        pose, v, a = self.q_from(0), self.reg_float(6), self.reg_float(7)
        q = self.arm.inverse_kin(pose, None)
        if q is None:
            raise MotionError("get_inverse_kin found no solution for the target pose")
        self._move(lambda: self.arm.movej(q, a, v))

    def movel(self) -> None:
        pose, v, a = self.q_from(0), self.reg_float(6), self.reg_float(7)
        self._move(lambda: self.arm.movel(pose, a, v))

    def movel_fk(self) -> None:
        q, v, a = self.q_from(0), self.reg_float(6), self.reg_float(7)
        self._move(lambda: self.arm.movel_to_joints(q, a, v))

    def speedj(self) -> None:
        self.speeding = True
        self.arm.speedj(self.q_from(0), self.reg_float(6))

    def servoj(self) -> None:
        self.servoing = True
        self.arm.servoj(self.q_from(0), self.reg_float(8))

    def _block_on(self, start: Callable[[], MoveHandle]) -> None:
        """A URScript call that returns when the arm stands still (stopj, stopl): the loop waits for it."""
        self.blocking = (start(), start)

    def speed_stop(self) -> None:
        self.speeding = False
        decel = self.reg_float(0)
        self._block_on(lambda: self.arm.stopj(decel))  # speed_type 1 (speedj): stopj

    def servo_stop(self) -> None:
        self.servoing = False
        decel = self.reg_float(0)
        self._block_on(lambda: self.arm.stopl(decel))

    def stop_l_or_j(self) -> None:
        """``exec_stopl_stopj``: as the script does it, including its use of the global ``stop_type``."""
        decel, is_async = self.reg_float(0), self.reg_int(1) == 1
        stop_move = True
        if self.async_stop is not None:
            stop_move = False
            self.async_stop = None
            self.write_async_progress(-1)
        if stop_move:
            self._stop_async_move()
        if is_async:
            self.stop_type = 1
            self.async_stop = self.arm.stopl(decel)
            self.write_async_progress(0)
        elif self.stop_type == 0:
            self._block_on(lambda: self.arm.stopj(decel))
        else:
            self._block_on(lambda: self.arm.stopl(decel))

    def set_payload(self) -> None:
        self.arm.set_payload(self.reg_float(0), np.array([self.reg_float(1), self.reg_float(2), self.reg_float(3)]))

    def set_tcp(self) -> None:
        self.arm.set_tcp(self.q_from(0))

    def ik_args(self) -> None:
        q = self.arm.inverse_kin(self.q_from(0), self.q_from(6))
        if q is None:  # get_inverse_kin raises in URScript: the program stops
            raise MotionError("get_inverse_kin found no solution")
        self.to_floats(0, q)

    def ik_default(self) -> None:
        q = self.arm.inverse_kin(self.q_from(0), None)
        if q is None:
            raise MotionError("get_inverse_kin found no solution")
        self.to_floats(0, q)

    def ik_has_solution(self, with_args: bool) -> None:
        q = self.arm.inverse_kin(self.q_from(0), self.q_from(6) if with_args else None)
        self.out_int[1 + self.off] = int(q is not None)

    def protective_stop(self) -> None:
        # protective_stop() pauses the program inside the call: "done" is written only if it is resumed
        self.arm.protective_stop("the program asked for it (triggerProtectiveStop)")
        self.blocking = (_FINISHED, lambda: _FINISHED)

    def set_watchdog(self) -> None:
        self.arm.set_watchdog(f"input_int_register_{self.off}", self.reg_float(0))

    def within_limits(self, joints: bool) -> None:
        ok = self.arm.joints_within_limits(self.q_from(0)) if joints else self.arm.pose_within_limits(self.q_from(0))
        self.out_int[1 + self.off] = int(ok)

    def pose_trans(self) -> None:
        self.to_floats(0, self.arm.pose_trans(self.q_from(0), self.q_from(6)))

    def fk_args(self) -> None:
        # recipe 6 (q only) leaves registers 6..11 as they were: ur_rtde sends q alone when no TCP is given, and
        # the script reads registers 6..11 as the TCP anyway; a zero pose there means "the flange"
        self.to_floats(0, self.arm.forward_kin(self.q_from(0), self.q_from(6)))

    def is_steady(self) -> None:
        self.out_int[1 + self.off] = int(self.arm.is_steady())


_HANDLERS: dict[Code, Callable[[ControlProgram], None]] = {
    Code.MOVEJ: ControlProgram.movej,
    Code.MOVEJ_IK: ControlProgram.movej_ik,
    Code.MOVEL: ControlProgram.movel,
    Code.MOVEL_FK: ControlProgram.movel_fk,
    Code.SPEEDJ: ControlProgram.speedj,
    Code.SERVOJ: ControlProgram.servoj,
    Code.SPEED_STOP: ControlProgram.speed_stop,
    Code.SERVO_STOP: ControlProgram.servo_stop,
    Code.SET_PAYLOAD: ControlProgram.set_payload,
    Code.SET_TCP: ControlProgram.set_tcp,
    Code.GET_INVERSE_KINEMATICS_ARGS: ControlProgram.ik_args,
    Code.GET_INVERSE_KINEMATICS_DEFAULT: ControlProgram.ik_default,
    Code.GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT: lambda p: p.ik_has_solution(False),
    Code.GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS: lambda p: p.ik_has_solution(True),
    Code.PROTECTIVE_STOP: ControlProgram.protective_stop,
    Code.STOPL: ControlProgram.stop_l_or_j,
    Code.STOPJ: ControlProgram.stop_l_or_j,
    Code.SET_WATCHDOG: ControlProgram.set_watchdog,
    Code.IS_POSE_WITHIN_SAFETY_LIMITS: lambda p: p.within_limits(False),
    Code.IS_JOINTS_WITHIN_SAFETY_LIMITS: lambda p: p.within_limits(True),
    Code.POSE_TRANS: ControlProgram.pose_trans,
    Code.GET_TCP_OFFSET: lambda p: p.to_floats(0, p.arm.tcp_offset()),
    Code.GET_FORWARD_KINEMATICS_DEFAULT: lambda p: p.to_floats(0, p.arm.forward_kin(None, None)),
    Code.GET_FORWARD_KINEMATICS_ARGS: ControlProgram.fk_args,
    Code.IS_STEADY: ControlProgram.is_steady,
    Code.GET_ACTUAL_TOOL_FLANGE_POSE: lambda p: p.to_floats(0, p.arm.flange_pose()),
}
