"""RTDE's wire format, from Universal Robots' RTDE guide (protocol version 2): package types, field types, the
controller's named input and output fields, and their packing.

Every package is ``uint16 size`` (header included) + ``uint8 type`` + payload, all big-endian (network order).
The field names and types below are the guide's tables for a CB3 controller of PolyScope 3.15 (the twin's UR5);
a name the table does not hold is answered ``NOT_FOUND`` in a setup reply, as a controller does.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Sequence
from dataclasses import dataclass

HEADER = struct.Struct(">HB")
#: the largest package the twin accepts from a client (a recipe of every input field is ~3 KB of names)
MAX_PACKAGE_BYTES = 8192
PROTOCOL_VERSION = 2


class PackageType(enum.IntEnum):
    """The package types of the guide (ASCII letters on the wire)."""

    REQUEST_PROTOCOL_VERSION = 86  # 'V'
    GET_URCONTROL_VERSION = 118  # 'v'
    TEXT_MESSAGE = 77  # 'M'
    DATA_PACKAGE = 85  # 'U'
    CONTROL_PACKAGE_SETUP_OUTPUTS = 79  # 'O'
    CONTROL_PACKAGE_SETUP_INPUTS = 73  # 'I'
    CONTROL_PACKAGE_START = 83  # 'S'
    CONTROL_PACKAGE_PAUSE = 80  # 'P'


class MessageLevel(enum.IntEnum):
    """A text message's warning level (protocol version 2)."""

    EXCEPTION = 0
    ERROR = 1
    WARNING = 2
    INFO = 3


class FieldType(enum.Enum):
    """A field's type: its name in setup replies and its struct format."""

    BOOL = ("BOOL", "?")
    UINT8 = ("UINT8", "B")
    UINT32 = ("UINT32", "I")
    UINT64 = ("UINT64", "Q")
    INT32 = ("INT32", "i")
    DOUBLE = ("DOUBLE", "d")
    VECTOR3D = ("VECTOR3D", "3d")
    VECTOR6D = ("VECTOR6D", "6d")
    VECTOR6INT32 = ("VECTOR6INT32", "6i")
    VECTOR6UINT32 = ("VECTOR6UINT32", "6I")

    def __init__(self, wire_name: str, fmt: str) -> None:
        self.wire_name = wire_name
        self.fmt = fmt

    @property
    def count(self) -> int:
        """How many numbers the field holds (1 for scalars)."""
        return int(self.fmt[:-1]) if len(self.fmt) > 1 else 1


T = FieldType
_OUTPUT_FIELDS: dict[str, FieldType] = {
    "timestamp": T.DOUBLE,
    "target_q": T.VECTOR6D, "target_qd": T.VECTOR6D, "target_qdd": T.VECTOR6D, "target_current": T.VECTOR6D,
    "target_moment": T.VECTOR6D, "actual_q": T.VECTOR6D, "actual_qd": T.VECTOR6D, "actual_current": T.VECTOR6D,
    "joint_control_output": T.VECTOR6D, "actual_TCP_pose": T.VECTOR6D, "actual_TCP_speed": T.VECTOR6D,
    "actual_TCP_force": T.VECTOR6D, "target_TCP_pose": T.VECTOR6D, "target_TCP_speed": T.VECTOR6D,
    "actual_digital_input_bits": T.UINT64, "joint_temperatures": T.VECTOR6D, "actual_execution_time": T.DOUBLE,
    "robot_mode": T.INT32, "joint_mode": T.VECTOR6INT32, "safety_mode": T.INT32, "safety_status": T.INT32,
    "actual_tool_accelerometer": T.VECTOR3D, "speed_scaling": T.DOUBLE, "target_speed_fraction": T.DOUBLE,
    "actual_momentum": T.DOUBLE, "actual_main_voltage": T.DOUBLE, "actual_robot_voltage": T.DOUBLE,
    "actual_robot_current": T.DOUBLE, "actual_joint_voltage": T.VECTOR6D, "actual_digital_output_bits": T.UINT64,
    "runtime_state": T.UINT32, "elbow_position": T.VECTOR3D, "elbow_velocity": T.VECTOR3D,
    "robot_status_bits": T.UINT32, "safety_status_bits": T.UINT32, "analog_io_types": T.UINT32,
    "standard_analog_input0": T.DOUBLE, "standard_analog_input1": T.DOUBLE, "standard_analog_output0": T.DOUBLE,
    "standard_analog_output1": T.DOUBLE, "io_current": T.DOUBLE, "euromap67_input_bits": T.UINT32,
    "euromap67_output_bits": T.UINT32, "euromap67_24V_voltage": T.DOUBLE, "euromap67_24V_current": T.DOUBLE,
    "tool_mode": T.UINT32, "tool_analog_input_types": T.UINT32, "tool_analog_input0": T.DOUBLE,
    "tool_analog_input1": T.DOUBLE, "tool_output_voltage": T.INT32, "tool_output_current": T.DOUBLE,
    "tool_temperature": T.DOUBLE, "tcp_force_scalar": T.DOUBLE, "output_bit_registers0_to_31": T.UINT32,
    "output_bit_registers32_to_63": T.UINT32, "input_bit_registers0_to_31": T.UINT32,
    "input_bit_registers32_to_63": T.UINT32, "payload": T.DOUBLE, "payload_cog": T.VECTOR3D,
    "payload_inertia": T.VECTOR6D, "script_control_line": T.UINT32,
}
_INPUT_FIELDS: dict[str, FieldType] = {
    "speed_slider_mask": T.UINT32, "speed_slider_fraction": T.DOUBLE,
    "standard_digital_output_mask": T.UINT8, "standard_digital_output": T.UINT8,
    "configurable_digital_output_mask": T.UINT8, "configurable_digital_output": T.UINT8,
    "tool_digital_output_mask": T.UINT8, "tool_digital_output": T.UINT8,
    "standard_analog_output_mask": T.UINT8, "standard_analog_output_type": T.UINT8,
    "standard_analog_output_0": T.DOUBLE, "standard_analog_output_1": T.DOUBLE,
    "input_bit_registers0_to_31": T.UINT32, "input_bit_registers32_to_63": T.UINT32,
    "external_force_torque": T.VECTOR6D,
}
#: general-purpose registers: 0-23 are the "lower range", 24-47 the upper range (PolyScope 3.9+)
REGISTER_COUNT = 48
BIT_REGISTERS = range(64, 128)  # the individually addressable bit registers


def _with_registers(fields: dict[str, FieldType], direction: str) -> dict[str, FieldType]:
    out = dict(fields)
    for i in range(REGISTER_COUNT):
        out[f"{direction}_int_register_{i}"] = T.INT32
        out[f"{direction}_double_register_{i}"] = T.DOUBLE
    for i in BIT_REGISTERS:
        out[f"{direction}_bit_register_{i}"] = T.BOOL
    return out


#: every field a client may ask the controller to send (outputs; the input registers can be read back too)
OUTPUT_FIELDS: dict[str, FieldType] = _with_registers(_with_registers(_OUTPUT_FIELDS, "output"), "input")
#: every field a client may write (inputs)
INPUT_FIELDS: dict[str, FieldType] = _with_registers(_INPUT_FIELDS, "input")

NOT_FOUND = "NOT_FOUND"
IN_USE = "IN_USE"


@dataclass(frozen=True)
class Recipe:
    """A recipe: the named fields of a data package, in order, with the struct that packs them."""

    recipe_id: int
    names: tuple[str, ...]
    types: tuple[FieldType, ...]

    @property
    def layout(self) -> struct.Struct:
        return struct.Struct(">B" + "".join(t.fmt for t in self.types))

    def pack(self, values: Sequence[float | int | bool | Sequence[float | int]]) -> bytes:
        """A data package (header included) of this recipe with one value per field (vectors as sequences)."""
        flat: list[float | int | bool] = [self.recipe_id]
        for field_type, value in zip(self.types, values, strict=True):
            if field_type.count == 1:
                flat.append(value)  # type: ignore[arg-type]
            else:
                flat.extend(value)  # type: ignore[arg-type]
        body = self.layout.pack(*flat)
        return HEADER.pack(HEADER.size + len(body), PackageType.DATA_PACKAGE) + body

    def unpack(self, payload: bytes) -> tuple[object, ...]:
        """The field values of a data package's payload (recipe id first byte included); ValueError if the
        size does not match this recipe."""
        layout = self.layout
        if len(payload) != layout.size:
            raise ValueError(f"recipe {self.recipe_id} needs {layout.size} bytes, the package has {len(payload)}")
        flat = layout.unpack(payload)[1:]
        values: list[object] = []
        i = 0
        for field_type in self.types:
            n = field_type.count
            values.append(flat[i] if n == 1 else tuple(flat[i:i + n]))
            i += n
        return tuple(values)


def package(kind: PackageType, payload: bytes = b"") -> bytes:
    """One package: header + payload."""
    return HEADER.pack(HEADER.size + len(payload), kind) + payload


def text_message(message: str, source: str, level: MessageLevel) -> bytes:
    """An RTDE_TEXT_MESSAGE package of protocol version 2 (each string at most 255 bytes)."""
    msg = message.encode("utf-8", "replace")[:255]
    src = source.encode("utf-8", "replace")[:255]
    return package(PackageType.TEXT_MESSAGE, bytes([len(msg)]) + msg + bytes([len(src)]) + src + bytes([level]))


def parse_names(payload: bytes) -> list[str]:
    """The variable names of a setup request: comma-separated ASCII (a trailing comma, as ur_rtde sends, and
    surrounding blanks are ignored). ValueError on bytes that are not printable ASCII."""
    try:
        text = payload.decode("ascii")
    except UnicodeDecodeError as exc:
        raise ValueError("the variable names are not ASCII") from exc
    if not text.isprintable():
        raise ValueError("the variable names hold control characters")
    names = [n.strip() for n in text.split(",")]
    if names and names[-1] == "":
        names.pop()
    return names
