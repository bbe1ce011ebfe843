"""The command codes of ur_rtde 1.6.5's control script (``RTDE::RobotCommand::Type``) and which the twin runs.

A client writes a code into ``input_int_register_0`` (plus the register offset) and its arguments into the input
registers; the script answers through ``output_int_register_0`` (1: ready for a command, 2: done with it) and,
for queries, the output registers. Codes in :data:`REALTIME_CODES` are processed every cycle while they stay in
the register (servoing, speeding) and answered "ready" at once; the others run once per write.
"""

from __future__ import annotations

import enum


class Code(enum.IntEnum):
    NO_CMD = 0
    MOVEJ = 1
    MOVEJ_IK = 2
    MOVEL = 3
    MOVEL_FK = 4
    FORCE_MODE = 6
    FORCE_MODE_STOP = 7
    ZERO_FT_SENSOR = 8
    SPEEDJ = 9
    SPEEDL = 10
    SERVOJ = 11
    SERVOC = 12
    SPEED_STOP = 15
    SERVO_STOP = 16
    SET_PAYLOAD = 17
    SERVOL = 24
    GET_TARGET_WAYPOINT = 28
    SET_TCP = 29
    GET_INVERSE_KINEMATICS_ARGS = 30
    PROTECTIVE_STOP = 31
    STOPL = 33
    STOPJ = 34
    SET_WATCHDOG = 35
    IS_POSE_WITHIN_SAFETY_LIMITS = 36
    IS_JOINTS_WITHIN_SAFETY_LIMITS = 37
    POSE_TRANS = 39
    GET_TCP_OFFSET = 40
    GET_FORWARD_KINEMATICS_DEFAULT = 43
    GET_FORWARD_KINEMATICS_ARGS = 44
    MOVE_PATH = 45
    GET_INVERSE_KINEMATICS_DEFAULT = 46
    IS_STEADY = 47
    GET_ACTUAL_TOOL_FLANGE_POSE = 58
    GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT = 60
    GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS = 61
    INTERNAL = 254
    STOP_SCRIPT = 255


#: processed every cycle while in the register, answered "ready" at once (the script's main loop's list)
REALTIME_CODES = frozenset({24, 11, 9, 10, 6, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71})

#: the codes the twin carries out (docs/twin.md lists them with the ur_rtde call that sends each)
SUPPORTED = frozenset({
    Code.NO_CMD, Code.MOVEJ, Code.MOVEJ_IK, Code.MOVEL, Code.MOVEL_FK, Code.SPEEDJ, Code.SERVOJ, Code.SPEED_STOP,
    Code.SERVO_STOP, Code.SET_PAYLOAD, Code.SET_TCP, Code.GET_INVERSE_KINEMATICS_ARGS, Code.PROTECTIVE_STOP,
    Code.STOPL, Code.STOPJ, Code.SET_WATCHDOG, Code.IS_POSE_WITHIN_SAFETY_LIMITS, Code.IS_JOINTS_WITHIN_SAFETY_LIMITS,
    Code.POSE_TRANS, Code.GET_TCP_OFFSET, Code.GET_FORWARD_KINEMATICS_DEFAULT, Code.GET_FORWARD_KINEMATICS_ARGS,
    Code.GET_INVERSE_KINEMATICS_DEFAULT, Code.IS_STEADY, Code.GET_ACTUAL_TOOL_FLANGE_POSE,
    Code.GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT, Code.GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS,
    Code.STOP_SCRIPT,
})

READY_FOR_COMMAND = 1
DONE_WITH_COMMAND = 2
