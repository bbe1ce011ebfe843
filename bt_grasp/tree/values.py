"""BehaviorTree.CPP's value model (``BT::Any``), as scripts, ports and the blackboard see it.

A value is one of:

* an **integer** (``int``): BT.CPP's ``int64``; a script integer literal, an ``int`` port;
* a **real** (``float``): BT.CPP's ``double``; the result of every arithmetic, comparison and logic operator,
  ``true``/``false`` literals and scripting enums read by a script;
* a **bool** (``bool``): a value written by a ``bool`` port (LoopBool, a leaf); a number 0/1 underneath;
* a **string** (``str``);
* any other object a leaf wrote (a pose, a list of detections): scripts cannot compute with it.

The conversions are BT.CPP's (``safe_any.hpp``, ``convert_impl.hpp``): a real becomes an integer only when it
has no fraction, an integer becomes a bool only when it is 0 or 1, a string is never a bool, a real turns into
text with six decimals (``std::to_string``: ``2.000000``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import TypeGuard

from bt_grasp.tree.exceptions import TreeRuntimeError

#: BT.CPP compares reals with ``std::numeric_limits<float>::epsilon()``
EPSILON = 1.1920928955078125e-07
_INT64_MIN, _INT64_MAX = -(2**63), 2**63 - 1
_MAX_EXACT = 2**53 - 1

#: the Python types BT.CPP's ``Any`` has a counterpart for
SCALAR_TYPES: tuple[type, ...] = (bool, int, float, str)


def is_scalar(value: object) -> TypeGuard[bool | int | float | str]:
    return isinstance(value, bool | int | float | str)


def is_number(value: object) -> TypeGuard[int | float]:
    """``Any::isNumber``: integers, reals and bools (a bool is an integer underneath)."""
    return isinstance(value, int | float)


def type_name(value: object) -> str:
    """The C++ type name BT.CPP would print in an error message."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int64_t"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "std::string"
    return type(value).__name__


def to_text(value: object) -> str:
    """``Any::cast<std::string>``: how BT.CPP turns a value into text (``..``, string ports, dumps)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "-nan" if math.copysign(1.0, value) < 0 else "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return f"{value:f}"
    return str(value)


def display(value: object) -> str:
    """A value as a user reads it (blackboard dumps, replay text): BT.CPP's text for numbers (a real with six
    decimals, ``2.000000``), ``true``/``false`` for a bool (BT.CPP's ``toStr<bool>``), text as it is."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if is_scalar(value):
        return to_text(value)
    return repr(value)


def parse_real(text: str, *, full: bool = True) -> float | None:
    """``std::from_chars<double>``: None when ``text`` is not a number (with ``full``: not wholly one)."""
    stripped = text
    if not stripped or stripped[0] in " \t\n+":
        return None
    try:
        return float(stripped) if full else float(_leading_number(stripped))
    except ValueError:
        return None


def _leading_number(text: str) -> str:
    end = 0
    for index in range(len(text), 0, -1):
        try:
            float(text[:index])
        except ValueError:
            continue
        end = index
        break
    return text[:end]


def parse_int(text: str) -> int | None:
    """``std::from_chars<int64_t>`` over the whole text; None when it is not an integer."""
    if not text or text[0] in " \t\n+" or not text.lstrip("-").isdigit():
        return None
    value = int(text)
    return value if _INT64_MIN <= value <= _INT64_MAX else None


_INT_PREFIX = re.compile(r"-?[0-9]+")
_REAL_PREFIX = re.compile(r"-?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|(?i:infinity|inf|nan))")


def int_prefix(text: str) -> tuple[int, str] | None:
    """``convertFromString<int64_t>`` (``std::from_chars``, the rest unchecked): the integer at the start of
    ``text`` and the text after it; None when none starts there (a leading space or ``+`` included) or it
    does not fit 64 bits. ``"2.7"`` reads 2, ``"0x10"`` reads 0, as BT.CPP reads them."""
    match = _INT_PREFIX.match(text)
    if match is None:
        return None
    value = int(match.group())
    if not _INT64_MIN <= value <= _INT64_MAX:
        return None
    return value, text[match.end() :]


def real_prefix(text: str) -> tuple[float, str] | None:
    """``convertFromString<double>`` (``std::from_chars``, the rest unchecked): the real at the start of
    ``text`` and the text after it; None when none starts there or it is out of range (``1e400``)."""
    match = _REAL_PREFIX.match(text)
    if match is None:
        return None
    value = float(match.group())
    if math.isinf(value) and "inf" not in match.group().lower():
        return None
    return value, text[match.end() :]


def to_real(value: object, enums: Mapping[str, int] | None = None) -> float:
    """A script operand as a real (``Any::cast<double>``; strings also read ``true``/``false``/enums,
    as ``StringToDouble`` does in comparisons)."""
    if is_number(value):
        return float(value)
    if isinstance(value, str):
        if enums is not None:
            if value == "true":
                return 1.0
            if value == "false":
                return 0.0
            if value in enums:
                return float(enums[value])
        number = parse_real(value)
        if number is None:
            raise TreeRuntimeError("Any failed string to number conversion")
        return number
    raise TreeRuntimeError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [double]")


def to_int(value: object) -> int:
    """``Any::cast<int64_t>``: a real must have no fraction and fit; a string must be an integer."""
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        if math.isnan(value) or value >= 2.0**63 or value < -(2.0**63) or value != math.floor(value):
            raise TreeRuntimeError("Invalid floating point to integer conversion")
        return int(value)
    if isinstance(value, str):
        number = parse_int(value)
        if number is None:
            raise TreeRuntimeError("Any failed string to number conversion")
        return number
    raise TreeRuntimeError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [int64_t]")


def to_bool(value: object) -> bool:
    """``Any::cast<bool>``: a real is true when not zero, an integer must be 0 or 1, a string is refused."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        if value not in (0, 1):
            raise TreeRuntimeError("Implicit casting to bool is not allowed")
        return bool(value)
    if isinstance(value, float):
        return value != 0.0
    raise TreeRuntimeError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [bool]")


def real_from_int(value: int) -> float:
    """An integer as a real, refusing integers a double cannot hold exactly (BT.CPP ``checkTruncation``)."""
    if abs(value) > _MAX_EXACT:
        raise TreeRuntimeError(f"Loss of precision when converting a large integer number to floating point:{value}")
    return float(value)


def copy_into(value: object, current: object) -> object:
    """``Any::copyInto``: ``value`` converted to the type ``current`` holds (raises when impossible)."""
    if isinstance(current, str) and isinstance(value, str):
        return value
    if type(current) is type(value) and not (isinstance(value, bool) ^ isinstance(current, bool)):
        return value
    if is_number(value) and is_number(current):
        if isinstance(current, bool):
            number = to_int(value)
            return bool(number) if number in (0, 1) else number
        if isinstance(current, int):
            return to_int(value)
        return real_from_int(value) if isinstance(value, int) else float(value)
    if is_scalar(value) or is_scalar(current):
        raise TreeRuntimeError(f"Any::copyInto fails: [{type_name(value)}] into [{type_name(current)}]")
    return value


def convert_text(text: str, kind: type) -> object:
    """``convertFromString<T>`` for the scalar port types (``int``, ``float``, ``bool``, ``str``): a number is
    read from the start of the text and the rest ignored (``std::from_chars``; no leading space or ``+``), a
    bool is one of BT.CPP's seven spellings exactly."""
    if kind is str:
        return text
    if kind is bool:
        if text in ("true", "True", "TRUE", "1"):
            return True
        if text in ("false", "False", "FALSE", "0"):
            return False
        raise TreeRuntimeError(f"Can't convert string [{text}] to bool")
    if kind is int:
        number = int_prefix(text)
        if number is None:
            raise TreeRuntimeError(f"Can't convert string [{text}] to integer")
        return number[0]
    if kind is float:
        real = real_prefix(text)
        if real is None:
            raise TreeRuntimeError(f"Can't convert string [{text}] to double")
        return real[0]
    parse = getattr(kind, "from_port_text", None)
    if callable(parse):  # an application type (registry.is_text_port_type)
        try:
            return parse(text)
        except ValueError as exc:
            raise TreeRuntimeError(str(exc)) from None
    return text


def cast_to(value: object, kind: type) -> object:
    """A blackboard value read through a port of type ``kind`` (BT.CPP ``getInput<T>``)."""
    if kind is object:
        return value
    if isinstance(value, str):
        return convert_text(value, kind)
    if kind is str:
        return to_text(value)
    if not is_number(value) or kind not in (bool, int, float):  # an application type takes only its own values
        if isinstance(value, kind):
            return value
        name = getattr(kind, "__name__", str(kind))
        raise TreeRuntimeError(f"[Any::convert]: no known safe conversion between [{type_name(value)}] and [{name}]")
    if kind is bool:
        return to_bool(value)
    if kind is int:
        return to_int(value)
    return real_from_int(value) if isinstance(value, int) and not isinstance(value, bool) else float(value)


def literal_value(text: str) -> int | float | str:
    """A literal written on a ``<SubTree>`` port: an integer, else a real, else the text (BT.CPP 4.10)."""
    if text and "." not in text and "e" not in text and "E" not in text:
        number = parse_int(text)
        if number is not None:
            return number
    real = parse_real(text) if text else None
    return real if real is not None else text
