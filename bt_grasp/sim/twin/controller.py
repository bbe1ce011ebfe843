"""The twin's UR controller: one :meth:`Controller.tick` per controller cycle, in real time.

A cycle: take the inputs RTDE clients wrote; apply I/O requests (speed slider, digital and analog outputs);
check the RTDE watchdog; run one pass of the control program (if one plays); step the physics one cycle with the
arm's commanded joint state fed to the drives at every physics step; step the gripper; look for a collision;
then report the state (RTDE publishes it). Everything a dashboard, script or control connection changes goes
through the same lock, so it lands between two cycles, as on a controller.

The safety and program states follow a UR's: a protective stop halts the arm and pauses the program (the
dashboard's ``unlock protective stop`` clears it, no sooner than ``unlock_delay_s``; ``play`` resumes the
program, or a client uploads its script again); stopping the program (dashboard ``stop``, the pendant, a fired
watchdog, a script error) halts the arm and ends the program.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from bt_grasp.sim.twin.arm import TwinArm
from bt_grasp.sim.twin.config import TwinConfig
from bt_grasp.sim.twin.control_script import ControlScript
from bt_grasp.sim.twin.kinematics import UrKinematics
from bt_grasp.sim.twin.motion import MotionError, T_to_pose
from bt_grasp.sim.twin.plant import Plant
from bt_grasp.sim.twin.robotiq import Robotiq2F85
from bt_grasp.sim.twin.rtde_types import REGISTER_COUNT
from bt_grasp.sim.twin.script_program import ControlProgram, ProgramEnd
from bt_grasp.sim.twin.state import ControllerState, InputBank, RobotMode, RuntimeState, SafetyMode

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]


class Controller:
    def __init__(self, config: TwinConfig, plant: Plant, kin: UrKinematics, inputs: InputBank,
                 T_flange_tcp: NDArray[np.float64], gripper: Robotiq2F85 | None = None) -> None:
        self.config = config
        self.plant = plant
        self.kin = kin
        self.inputs = inputs
        self.gripper = gripper
        self.lock = threading.RLock()
        self.out_int = [0] * REGISTER_COUNT
        self.out_double = [0.0] * REGISTER_COUNT
        self.robot_mode = RobotMode.RUNNING
        self.safety_mode = SafetyMode.NORMAL
        self.runtime_state = RuntimeState.STOPPED
        self.program: ControlProgram | None = None
        self.protective_stop_at: float | None = None
        self.watchdog: tuple[str, float] | None = None  # (input field, longest gap s)
        self.speed_fraction = 1.0
        self._slider_enabled = False
        self._masks: dict[str, int] = {}
        self._watchdog_armed = 0.0
        self.digital_outputs = 0
        self.analog_outputs = (0.0, 0.0)
        self.cycle = 0
        self.steps_per_cycle = max(1, round(config.period_s / plant.dt_s))
        q0, _ = plant.joint_state()
        self.arm = TwinArm(kin, q0, T_flange_tcp, plant.joint_state, self.protective_stop, self._set_watchdog)
        self.state = ControllerState()
        self._last_tcp: tuple[Vec, Vec] | None = None
        #: called with the cycle's state, under the lock, after each cycle (the judge's observer, tests)
        self.after_cycle: list[Callable[[ControllerState], None]] = []

    # --- the cycle ------------------------------------------------------------------------------------
    def tick(self) -> ControllerState:
        start = time.perf_counter()
        ints, doubles, bits, io = self.inputs.snapshot()
        with self.lock:
            for name, value in io:
                self._apply_io(name, value)
            self._check_watchdog()
            if self.program is not None and self._may_move() and self.runtime_state == RuntimeState.PLAYING:
                try:
                    self.program.step(ints, doubles)
                except ProgramEnd as end:
                    self.stop_program(str(end))
            dt = self.plant.dt_s
            for _ in range(self.steps_per_cycle):
                try:
                    q, qd = self.arm.advance(dt, self.speed_fraction)
                except MotionError as exc:  # a movel met a pose without a solution on its way
                    self.stop_program(f"the motion failed: {exc}")
                    q, qd = self.arm.advance(dt, self.speed_fraction)
                if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):  # never reaches the drives
                    self.stop_program("the commanded motion was not finite")
                    self.arm.hold_actual()
                    q, qd = self.arm.advance(dt, self.speed_fraction)
                self.plant.set_joint_targets(q, qd)
                self.plant.step()
            if self.gripper is not None:
                self.gripper.step(self.steps_per_cycle * dt)
            if self.safety_mode == SafetyMode.NORMAL:
                hit = self.plant.collision(self.config.collision_force_n)
                if hit is not None:
                    self.protective_stop(f"collision: {hit}")
            self.cycle += 1
            self.state = self._report(ints, doubles, bits, (time.perf_counter() - start) * 1000.0)
            for observer in self.after_cycle:
                observer(self.state)
            return self.state

    def _may_move(self) -> bool:
        return self.robot_mode == RobotMode.RUNNING and self.safety_mode == SafetyMode.NORMAL

    def _apply_io(self, name: str, value: object) -> None:
        v = int(value) if isinstance(value, int | bool) else value
        if name == "speed_slider_fraction" and self._slider_enabled:
            self.speed_fraction = min(1.0, max(0.0, float(v)))  # type: ignore[arg-type]
        elif name == "speed_slider_mask":
            self._slider_enabled = bool(int(v) & 1)  # type: ignore[call-overload]
        elif name in ("standard_digital_output", "configurable_digital_output", "tool_digital_output"):
            shift = {"standard_digital_output": 0, "configurable_digital_output": 8, "tool_digital_output": 16}[name]
            mask = self._masks.get(name, 0) << shift
            self.digital_outputs = (self.digital_outputs & ~mask) | ((int(v) << shift) & mask)  # type: ignore[call-overload]
        elif name.endswith("_mask"):
            self._masks[name.removesuffix("_mask")] = int(v)  # type: ignore[call-overload]
        elif name in ("standard_analog_output_0", "standard_analog_output_1"):
            index = int(name[-1])
            if self._masks.get("standard_analog_output", 0) & (1 << index):
                outputs = list(self.analog_outputs)
                outputs[index] = float(v)  # type: ignore[arg-type]
                self.analog_outputs = (outputs[0], outputs[1])
        # standard_analog_output_type, external_force_torque: accepted, nothing simulated

    def _report(self, ints: tuple[int, ...], doubles: tuple[float, ...], bits: int,
                execution_ms: float) -> ControllerState:
        q, qd = self.plant.joint_state()
        tcp = self.arm.T_flange_tcp
        actual_pose = T_to_pose(self.kin.T_base_tcp(q, tcp))
        target_pose = T_to_pose(self.kin.T_base_tcp(self.arm.q_cmd, tcp))
        period = self.config.period_s
        if self._last_tcp is None:
            actual_speed, target_speed = np.zeros(6), np.zeros(6)
        else:
            actual_speed = _pose_rate(self._last_tcp[0], actual_pose, period)
            target_speed = _pose_rate(self._last_tcp[1], target_pose, period)
        self._last_tcp = (actual_pose, target_pose)
        return ControllerState(
            timestamp_s=self.cycle * period, target_q=self.arm.q_cmd.copy(), target_qd=self.arm.qd_cmd.copy(),
            actual_q=q, actual_qd=qd, actual_tcp_pose=actual_pose, actual_tcp_speed=actual_speed,
            target_tcp_pose=target_pose, target_tcp_speed=target_speed, execution_time_ms=execution_ms,
            robot_mode=self.robot_mode, safety_mode=self.safety_mode, runtime_state=self.runtime_state,
            speed_fraction=self.speed_fraction, digital_output_bits=self.digital_outputs,
            analog_outputs=self.analog_outputs, payload_kg=self.arm.payload_kg,
            payload_cog_m=(float(self.arm.payload_cog_m[0]), float(self.arm.payload_cog_m[1]),
                           float(self.arm.payload_cog_m[2])),
            output_int=tuple(self.out_int), output_double=tuple(self.out_double), input_int=ints,
            input_double=doubles, input_bits=bits,
        )

    # --- the watchdog ------------------------------------------------------------------------------------
    def _set_watchdog(self, field: str, min_frequency_hz: float) -> None:
        if not min_frequency_hz > 0:
            self.watchdog = None
            return
        self.watchdog = (field, 1.0 / min_frequency_hz)
        self._watchdog_armed = time.monotonic()
        log.info("RTDE watchdog on %s: at least %g Hz", field, min_frequency_hz)

    def _check_watchdog(self) -> None:
        if self.watchdog is None or self.runtime_state != RuntimeState.PLAYING:
            return
        field, gap = self.watchdog
        last = max(self.inputs.last_update(field) or 0.0, self._watchdog_armed)
        silent = time.monotonic() - last
        if silent > gap:
            self.stop_program(f"the RTDE watchdog fired: {field} was not written for {silent * 1000:.0f} ms "
                              f"(it asked for at least {1 / gap:g} Hz)")

    # --- program and safety (any thread, under the lock) -------------------------------------------------
    def load_program(self, script: ControlScript) -> str | None:
        """A recognised control script arrived: it replaces any program. Returns a refusal sentence or None."""
        with self.lock:
            if self.robot_mode != RobotMode.RUNNING:
                return (f"the robot is {self.robot_mode.name.lower().replace('_', ' ')} (power on and release the "
                        "brakes first); the control script was not run")
            if self.safety_mode != SafetyMode.NORMAL:
                return f"the robot is in {self.safety_mode.name.lower().replace('_', ' ')}; the script was not run"
            if self.program is not None and self.runtime_state == RuntimeState.PLAYING:
                self.arm.halt(self.config.stop_decel_rad_s2)
            self.out_int[:] = [0] * REGISTER_COUNT
            self.out_double[:] = [0.0] * REGISTER_COUNT
            self.watchdog = None
            self.program = ControlProgram(self.arm, script.register_offset, self.out_int, self.out_double)
            self.runtime_state = RuntimeState.PLAYING
            log.info("control script started (%s, register offset %d)", script.flavour, script.register_offset)
            return None

    def stop_program(self, reason: str) -> None:
        with self.lock:
            if self.program is None and self.runtime_state == RuntimeState.STOPPED:
                return
            was = self.runtime_state
            self.program = None
            self.watchdog = None
            self.runtime_state = RuntimeState.STOPPED
            if self.robot_mode == RobotMode.RUNNING:
                self.arm.halt(self.config.stop_decel_rad_s2)
            log.warning("program stopped (was %s): %s", was.name.lower(), reason)

    def pause_program(self, reason: str) -> bool:
        with self.lock:
            if self.runtime_state != RuntimeState.PLAYING:
                return False
            self.runtime_state = RuntimeState.PAUSED
            self.arm.halt(self.config.stop_decel_rad_s2)
            log.warning("program paused: %s", reason)
            return True

    def play(self) -> bool:
        """Resume a paused program (False when there is none or the robot may not move)."""
        with self.lock:
            if self.program is None or self.runtime_state != RuntimeState.PAUSED or not self._may_move():
                return False
            self.runtime_state = RuntimeState.PLAYING
            self.program.resume()
            log.info("program resumed")
            return True

    def protective_stop(self, reason: str) -> None:
        with self.lock:
            if self.safety_mode == SafetyMode.PROTECTIVE_STOP:
                return
            self.safety_mode = SafetyMode.PROTECTIVE_STOP
            self.protective_stop_at = time.monotonic()
            self.arm.halt(self.config.stop_decel_rad_s2, from_actual=True)
            if self.runtime_state == RuntimeState.PLAYING:
                self.runtime_state = RuntimeState.PAUSED
            log.warning("protective stop: %s", reason)

    def unlock_protective_stop(self) -> float:
        """Clear a protective stop; returns 0, or the seconds still to wait (nothing cleared then)."""
        with self.lock:
            if self.safety_mode != SafetyMode.PROTECTIVE_STOP or self.protective_stop_at is None:
                return 0.0
            left = self.config.unlock_delay_s - (time.monotonic() - self.protective_stop_at)
            if left > 0:
                return left
            self.safety_mode = SafetyMode.NORMAL
            self.protective_stop_at = None
            log.info("protective stop unlocked")
            return 0.0

    def power_off(self) -> None:
        with self.lock:
            self.stop_program("the robot was powered off")
            self.robot_mode = RobotMode.POWER_OFF
            self.arm.hold_actual()

    def power_on(self) -> None:
        with self.lock:
            if self.robot_mode == RobotMode.POWER_OFF:
                self.robot_mode = RobotMode.IDLE
                self.arm.hold_actual()

    def brake_release(self) -> None:
        with self.lock:
            if self.robot_mode in (RobotMode.IDLE, RobotMode.POWER_ON):
                self.robot_mode = RobotMode.RUNNING
                self.arm.hold_actual()

    def snapshot(self) -> ControllerState:
        with self.lock:
            return replace(self.state)


def _pose_rate(before: Vec, after: Vec, dt: float) -> Vec:
    """A UR pose's rate: linear speed and the rotation vector's change, over one cycle."""
    return (np.asarray(after) - np.asarray(before)) / dt
