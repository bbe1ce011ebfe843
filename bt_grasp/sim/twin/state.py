"""The controller's state as RTDE reports it: UR's mode enumerations and bit fields, and the register banks.

The numbers are the ones a UR controller sends (RTDE guide; ur_rtde's ``RTDEControlInterface::SafetyStatus`` and
``RuntimeState`` use the same bits and values), so a client reads the twin's state with the code it reads a
robot's with.
"""

from __future__ import annotations

import enum
import threading
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bt_grasp.sim.twin.rtde_types import REGISTER_COUNT


class RobotMode(enum.IntEnum):
    NO_CONTROLLER = -1
    DISCONNECTED = 0
    CONFIRM_SAFETY = 1
    BOOTING = 2
    POWER_OFF = 3
    POWER_ON = 4
    IDLE = 5
    BACKDRIVE = 6
    RUNNING = 7
    UPDATING_FIRMWARE = 8


class SafetyMode(enum.IntEnum):
    NORMAL = 1
    REDUCED = 2
    PROTECTIVE_STOP = 3
    RECOVERY = 4
    SAFEGUARD_STOP = 5
    SYSTEM_EMERGENCY_STOP = 6
    ROBOT_EMERGENCY_STOP = 7
    VIOLATION = 8
    FAULT = 9


class RuntimeState(enum.IntEnum):
    STOPPING = 0
    STOPPED = 1
    PLAYING = 2
    PAUSING = 3
    PAUSED = 4
    RESUMING = 5


class SafetyBit(enum.IntEnum):
    """Bit numbers of ``safety_status_bits``."""

    NORMAL_MODE = 0
    REDUCED_MODE = 1
    PROTECTIVE_STOPPED = 2
    RECOVERY_MODE = 3
    SAFEGUARD_STOPPED = 4
    SYSTEM_EMERGENCY_STOPPED = 5
    ROBOT_EMERGENCY_STOPPED = 6
    EMERGENCY_STOPPED = 7
    VIOLATION = 8
    FAULT = 9
    STOPPED_DUE_TO_SAFETY = 10


class RobotStatusBit(enum.IntEnum):
    """Bit numbers of ``robot_status_bits``."""

    POWER_ON = 0
    PROGRAM_RUNNING = 1
    TEACH_BUTTON_PRESSED = 2
    POWER_BUTTON_PRESSED = 3


class JointMode(enum.IntEnum):
    POWER_OFF = 239
    RUNNING = 253
    IDLE = 255


def safety_bits(mode: SafetyMode) -> int:
    """``safety_status_bits`` for a safety mode."""
    if mode == SafetyMode.NORMAL:
        return 1 << SafetyBit.NORMAL_MODE
    if mode == SafetyMode.PROTECTIVE_STOP:
        return (1 << SafetyBit.PROTECTIVE_STOPPED) | (1 << SafetyBit.STOPPED_DUE_TO_SAFETY)
    if mode == SafetyMode.FAULT:
        return (1 << SafetyBit.FAULT) | (1 << SafetyBit.STOPPED_DUE_TO_SAFETY)
    return 1 << SafetyBit.STOPPED_DUE_TO_SAFETY


def _zeros6() -> NDArray[np.float64]:
    return np.zeros(6)


@dataclass
class ControllerState:
    """Everything the twin's RTDE outputs report for one controller cycle (SI units; poses in UR's base frame
    as ``[x, y, z, rx, ry, rz]`` with a rotation vector, as UR sends them)."""

    timestamp_s: float = 0.0
    target_q: NDArray[np.float64] = field(default_factory=_zeros6)
    target_qd: NDArray[np.float64] = field(default_factory=_zeros6)
    target_qdd: NDArray[np.float64] = field(default_factory=_zeros6)
    actual_q: NDArray[np.float64] = field(default_factory=_zeros6)
    actual_qd: NDArray[np.float64] = field(default_factory=_zeros6)
    actual_tcp_pose: NDArray[np.float64] = field(default_factory=_zeros6)
    actual_tcp_speed: NDArray[np.float64] = field(default_factory=_zeros6)
    target_tcp_pose: NDArray[np.float64] = field(default_factory=_zeros6)
    target_tcp_speed: NDArray[np.float64] = field(default_factory=_zeros6)
    execution_time_ms: float = 0.0
    robot_mode: RobotMode = RobotMode.RUNNING
    safety_mode: SafetyMode = SafetyMode.NORMAL
    runtime_state: RuntimeState = RuntimeState.STOPPED
    speed_fraction: float = 1.0
    digital_output_bits: int = 0
    analog_outputs: tuple[float, float] = (0.0, 0.0)
    payload_kg: float = 0.0
    payload_cog_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: the register banks at the end of the cycle (copies)
    output_int: tuple[int, ...] = (0,) * REGISTER_COUNT
    output_double: tuple[float, ...] = (0.0,) * REGISTER_COUNT
    output_bits: int = 0  # output bit registers 0-127
    input_int: tuple[int, ...] = (0,) * REGISTER_COUNT
    input_double: tuple[float, ...] = (0.0,) * REGISTER_COUNT
    input_bits: int = 0

    @property
    def program_running(self) -> bool:
        return self.runtime_state == RuntimeState.PLAYING

    @property
    def powered(self) -> bool:
        return self.robot_mode in (RobotMode.POWER_ON, RobotMode.IDLE, RobotMode.RUNNING, RobotMode.BACKDRIVE)

    @property
    def robot_status_bits(self) -> int:
        bits = (1 << RobotStatusBit.POWER_ON) if self.powered else 0
        if self.program_running:
            bits |= 1 << RobotStatusBit.PROGRAM_RUNNING
        return bits

    @property
    def safety_status_bits(self) -> int:
        return safety_bits(self.safety_mode)

    @property
    def joint_mode(self) -> int:
        if self.robot_mode == RobotMode.RUNNING:
            return JointMode.RUNNING
        return JointMode.IDLE if self.powered else JointMode.POWER_OFF


class InputBank:
    """The controller's input side, written by RTDE clients (any thread) and read once per cycle.

    Holds the general-purpose input registers, the I/O requests (digital/analog outputs, speed slider) and when
    each input field was last written (the RTDE watchdog's clock, monotonic seconds).
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.ints = [0] * REGISTER_COUNT
        self.doubles = [0.0] * REGISTER_COUNT
        self.bits = 0
        self.updated_at: dict[str, float] = {}
        self.io_requests: list[tuple[str, object]] = []

    def write(self, names: tuple[str, ...], values: tuple[object, ...]) -> None:
        """Apply one data package's fields atomically."""
        now = time.monotonic()
        with self._lock:
            for name, value in zip(names, values, strict=True):
                self.updated_at[name] = now
                if name.startswith("input_int_register_"):
                    self.ints[int(name.rsplit("_", 1)[1])] = int(value)  # type: ignore[call-overload]
                elif name.startswith("input_double_register_"):
                    self.doubles[int(name.rsplit("_", 1)[1])] = float(value)  # type: ignore[arg-type]
                elif name.startswith("input_bit_register_"):
                    bit = int(name.rsplit("_", 1)[1])
                    self.bits = (self.bits | (1 << bit)) if value else (self.bits & ~(1 << bit))
                elif name == "input_bit_registers0_to_31":
                    self.bits = (self.bits & ~0xFFFFFFFF) | int(value)  # type: ignore[call-overload]
                elif name == "input_bit_registers32_to_63":
                    self.bits = (self.bits & ~(0xFFFFFFFF << 32)) | (int(value) << 32)  # type: ignore[call-overload]
                else:
                    self.io_requests.append((name, value))

    def snapshot(self) -> tuple[tuple[int, ...], tuple[float, ...], int, list[tuple[str, object]]]:
        """(ints, doubles, bits, the I/O fields written since the last snapshot, in order)."""
        with self._lock:
            requests, self.io_requests = self.io_requests, []
            return tuple(self.ints), tuple(self.doubles), self.bits, requests

    def last_update(self, name: str) -> float | None:
        with self._lock:
            return self.updated_at.get(name)
