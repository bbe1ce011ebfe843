"""What each RTDE output field reads from the twin's :class:`ControllerState` (one table, compiled per recipe).

Fields the twin has no physics for report a constant a resting, healthy controller would (voltages, temperatures,
currents): ``docs/twin.md`` lists them. Every field of :data:`bt_grasp.sim.twin.rtde_types.OUTPUT_FIELDS` has an
entry here (``tests/twin/test_rtde_codec.py`` checks it).
"""

from __future__ import annotations

from collections.abc import Callable

from bt_grasp.sim.twin.rtde_types import BIT_REGISTERS, OUTPUT_FIELDS, REGISTER_COUNT
from bt_grasp.sim.twin.state import ControllerState

Getter = Callable[[ControllerState], object]

_ZERO6 = (0.0,) * 6
_ZERO3 = (0.0,) * 3
#: constants of a healthy, resting CB3 (reported, never simulated)
MAIN_VOLTAGE_V = 48.0
ROBOT_VOLTAGE_V = 48.0
ROBOT_CURRENT_A = 0.5
JOINT_VOLTAGE_V = 48.0
JOINT_TEMPERATURE_C = 30.0
TOOL_TEMPERATURE_C = 30.0
TOOL_OUTPUT_VOLTAGE_V = 24


def _vec(values: object) -> tuple[float, ...]:
    return tuple(float(v) for v in values)  # type: ignore[attr-defined]


_GETTERS: dict[str, Getter] = {
    "timestamp": lambda s: s.timestamp_s,
    "target_q": lambda s: _vec(s.target_q),
    "target_qd": lambda s: _vec(s.target_qd),
    "target_qdd": lambda s: _vec(s.target_qdd),
    "target_current": lambda s: _ZERO6,
    "target_moment": lambda s: _ZERO6,
    "actual_q": lambda s: _vec(s.actual_q),
    "actual_qd": lambda s: _vec(s.actual_qd),
    "actual_current": lambda s: _ZERO6,
    "joint_control_output": lambda s: _ZERO6,
    "actual_TCP_pose": lambda s: _vec(s.actual_tcp_pose),
    "actual_TCP_speed": lambda s: _vec(s.actual_tcp_speed),
    "actual_TCP_force": lambda s: _ZERO6,
    "target_TCP_pose": lambda s: _vec(s.target_tcp_pose),
    "target_TCP_speed": lambda s: _vec(s.target_tcp_speed),
    "actual_digital_input_bits": lambda s: 0,
    "joint_temperatures": lambda s: (JOINT_TEMPERATURE_C,) * 6,
    "actual_execution_time": lambda s: s.execution_time_ms,
    "robot_mode": lambda s: int(s.robot_mode),
    "joint_mode": lambda s: (s.joint_mode,) * 6,
    "safety_mode": lambda s: int(s.safety_mode),
    "safety_status": lambda s: int(s.safety_mode),
    "actual_tool_accelerometer": lambda s: (0.0, 0.0, -9.81),
    "speed_scaling": lambda s: 1.0,  # the trajectory limiter's own scaling: not modelled (the slider is below)
    "target_speed_fraction": lambda s: s.speed_fraction,
    "actual_momentum": lambda s: 0.0,
    "actual_main_voltage": lambda s: MAIN_VOLTAGE_V,
    "actual_robot_voltage": lambda s: ROBOT_VOLTAGE_V if s.powered else 0.0,
    "actual_robot_current": lambda s: ROBOT_CURRENT_A if s.powered else 0.0,
    "actual_joint_voltage": lambda s: (JOINT_VOLTAGE_V if s.powered else 0.0,) * 6,
    "actual_digital_output_bits": lambda s: s.digital_output_bits,
    "runtime_state": lambda s: int(s.runtime_state),
    "elbow_position": lambda s: _ZERO3,
    "elbow_velocity": lambda s: _ZERO3,
    "robot_status_bits": lambda s: s.robot_status_bits,
    "safety_status_bits": lambda s: s.safety_status_bits,
    "analog_io_types": lambda s: 0,
    "standard_analog_input0": lambda s: 0.0,
    "standard_analog_input1": lambda s: 0.0,
    "standard_analog_output0": lambda s: s.analog_outputs[0],
    "standard_analog_output1": lambda s: s.analog_outputs[1],
    "io_current": lambda s: 0.0,
    "euromap67_input_bits": lambda s: 0,
    "euromap67_output_bits": lambda s: 0,
    "euromap67_24V_voltage": lambda s: 0.0,
    "euromap67_24V_current": lambda s: 0.0,
    "tool_mode": lambda s: 0,
    "tool_analog_input_types": lambda s: 0,
    "tool_analog_input0": lambda s: 0.0,
    "tool_analog_input1": lambda s: 0.0,
    "tool_output_voltage": lambda s: TOOL_OUTPUT_VOLTAGE_V,
    "tool_output_current": lambda s: 0.0,
    "tool_temperature": lambda s: TOOL_TEMPERATURE_C,
    "tcp_force_scalar": lambda s: 0.0,
    "output_bit_registers0_to_31": lambda s: s.output_bits & 0xFFFFFFFF,
    "output_bit_registers32_to_63": lambda s: (s.output_bits >> 32) & 0xFFFFFFFF,
    "input_bit_registers0_to_31": lambda s: s.input_bits & 0xFFFFFFFF,
    "input_bit_registers32_to_63": lambda s: (s.input_bits >> 32) & 0xFFFFFFFF,
    "payload": lambda s: s.payload_kg,
    "payload_cog": lambda s: s.payload_cog_m,
    "payload_inertia": lambda s: _ZERO6,
    "script_control_line": lambda s: 0,
}


def _bank(attribute: str, index: int) -> Getter:
    return lambda s: getattr(s, attribute)[index]


def _bit(attribute: str, bit: int) -> Getter:
    return lambda s: bool((getattr(s, attribute) >> bit) & 1)


def _register_getters() -> dict[str, Getter]:
    out: dict[str, Getter] = {}
    for i in range(REGISTER_COUNT):
        for direction in ("output", "input"):
            out[f"{direction}_int_register_{i}"] = _bank(f"{direction}_int", i)
            out[f"{direction}_double_register_{i}"] = _bank(f"{direction}_double", i)
    for b in BIT_REGISTERS:
        out[f"output_bit_register_{b}"] = _bit("output_bits", b)
        out[f"input_bit_register_{b}"] = _bit("input_bits", b)
    return out


GETTERS: dict[str, Getter] = {**_GETTERS, **_register_getters()}
assert set(GETTERS) == set(OUTPUT_FIELDS), sorted(set(OUTPUT_FIELDS) ^ set(GETTERS))


def compile_recipe(names: tuple[str, ...]) -> Callable[[ControllerState], list[object]]:
    """The values of ``names`` (all known output fields) for a state, in order."""
    getters = [GETTERS[n] for n in names]

    def values(state: ControllerState) -> list[object]:
        return [g(state) for g in getters]

    return values
