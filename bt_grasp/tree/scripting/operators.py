"""The evaluated form of a BT.CPP script: small expression nodes with BT.CPP's value rules.

Values are Python ``bool``, ``int``, ``float``, ``str`` or any object a leaf wrote to the blackboard.
Numbers follow BT.CPP (which computes in ``double``): ``+ - *`` keep ints when both operands are ints,
``/`` always gives a float, ``==`` compares numbers with a float32 epsilon, a string compared with a number
is converted (``'true'`` is 1, an enum name is its value). ``&&`` and ``||`` evaluate both sides, as
BT.CPP does, and need numbers (``true``/``false`` are numbers).
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from bt_grasp.tree.blackboard import EMPTY, Blackboard
from bt_grasp.tree.exceptions import TreeRuntimeError

_EPS = 1.1920928955078125e-07  # std::numeric_limits<float>::epsilon()


@dataclass(frozen=True)
class Env:
    """What a script sees: the node's blackboard and the registry's scripting enums."""

    blackboard: Blackboard
    enums: Mapping[str, int]


def is_number(value: Any) -> bool:
    return isinstance(value, int | float)  # bool is an int


def truthy(value: Any) -> bool:
    """BT.CPP ``cast<bool>``: a number is true when not zero, a string must read as a boolean."""
    if is_number(value):
        return bool(value)
    if isinstance(value, str):
        lowered = value.strip()
        if lowered in ("true", "True", "TRUE", "1"):
            return True
        if lowered in ("false", "False", "FALSE", "0", ""):
            return False
    raise TreeRuntimeError(f"script: cannot use {value!r} as a boolean")


def string_to_number(value: str, env: Env) -> float:
    if value == "true":
        return 1.0
    if value == "false":
        return 0.0
    if value in env.enums:
        return float(env.enums[value])
    try:
        return float(value)
    except ValueError:
        raise TreeRuntimeError(f"script: cannot convert string {value!r} to a number") from None


def _as_number(value: Any) -> int | float:
    return int(value) if isinstance(value, bool) else value


class Expr:
    def evaluate(self, env: Env) -> Any:
        raise NotImplementedError


@dataclass(frozen=True)
class Literal(Expr):
    value: Any

    def evaluate(self, env: Env) -> Any:
        return self.value


@dataclass(frozen=True)
class Name(Expr):
    """An identifier: a scripting enum when registered, otherwise a blackboard variable."""

    name: str

    def evaluate(self, env: Env) -> Any:
        if self.name in env.enums:
            return env.enums[self.name]
        entry = env.blackboard.entry(self.name)
        if entry is None:
            raise TreeRuntimeError(f"script: variable not found: {self.name}")
        if entry.value is EMPTY:
            raise TreeRuntimeError(f"script: variable {self.name} has no value yet")
        return entry.value


@dataclass(frozen=True)
class Unary(Expr):
    op: str  # "-", "!", "~"
    operand: Expr

    def evaluate(self, env: Env) -> Any:
        value = self.operand.evaluate(env)
        if not is_number(value):
            raise TreeRuntimeError(f"script: operator {self.op} needs a number, got {value!r}")
        if self.op == "-":
            return -_as_number(value)
        if self.op == "!":
            return not value
        return float(~int(value))


_ARITH: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
    "/": operator.truediv,
}
_BITS: dict[str, Callable[[int, int], int]] = {"&": operator.and_, "|": operator.or_, "^": operator.xor}


def arithmetic(op: str, lhs: Any, rhs: Any) -> Any:
    if is_number(lhs) and is_number(rhs):
        if op in _ARITH:
            if op == "/" and rhs == 0:
                return float("inf") if lhs > 0 else float("-inf") if lhs < 0 else float("nan")
            return _ARITH[op](_as_number(lhs), _as_number(rhs))
        if op in _BITS:
            if float(lhs) != int(lhs) or float(rhs) != int(rhs):
                raise TreeRuntimeError("script: bitwise operators need integers")
            return _BITS[op](int(lhs), int(rhs))
        if op == "&&":
            return bool(lhs) and bool(rhs)
        if op == "||":
            return bool(lhs) or bool(rhs)
    if isinstance(lhs, str) and isinstance(rhs, str) and op == "+":
        return lhs + rhs
    texts = isinstance(lhs, str | int | float) and isinstance(rhs, str | int | float)
    if op == ".." and texts and (isinstance(lhs, str) or isinstance(rhs, str)):
        return _to_text(lhs) + _to_text(rhs)
    raise TreeRuntimeError(f"script: operation {lhs!r} {op} {rhs!r} is not permitted")


def _to_text(value: Any) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float) and value.is_integer():
        return str(value)
    return str(value)


@dataclass(frozen=True)
class Binary(Expr):
    op: str
    lhs: Expr
    rhs: Expr

    def evaluate(self, env: Env) -> Any:
        return arithmetic(self.op, self.lhs.evaluate(env), self.rhs.evaluate(env))


def _compare_pair(op: str, lhs: Any, rhs: Any, env: Env) -> bool:
    if is_number(lhs) and is_number(rhs):
        lv, rv = float(lhs), float(rhs)
    elif isinstance(lhs, str) and isinstance(rhs, str):
        return {"==": lhs == rhs, "!=": lhs != rhs, "<": lhs < rhs, ">": lhs > rhs,
                "<=": lhs <= rhs, ">=": lhs >= rhs}[op]  # fmt: skip
    elif isinstance(lhs, str) and is_number(rhs):
        lv, rv = string_to_number(lhs, env), float(rhs)
    elif is_number(lhs) and isinstance(rhs, str):
        lv, rv = float(lhs), string_to_number(rhs, env)
    else:
        if op in ("==", "!="):
            return (lhs == rhs) == (op == "==")
        raise TreeRuntimeError(f"script: cannot compare {lhs!r} {op} {rhs!r}")
    same = abs(lv - rv) <= _EPS
    if op == "==":
        return same
    if op == "!=":
        return not same
    return {"<": lv < rv, ">": lv > rv, "<=": lv <= rv, ">=": lv >= rv}[op]


@dataclass(frozen=True)
class Compare(Expr):
    """A chained comparison ``a < b < c`` (BT.CPP evaluates each adjacent pair)."""

    operands: tuple[Expr, ...]
    ops: tuple[str, ...]

    def evaluate(self, env: Env) -> Any:
        lhs = self.operands[0].evaluate(env)
        for op, operand in zip(self.ops, self.operands[1:], strict=True):
            rhs = operand.evaluate(env)
            if not _compare_pair(op, lhs, rhs, env):
                return False
            lhs = rhs
        return True


@dataclass(frozen=True)
class Ternary(Expr):
    condition: Expr
    then: Expr
    otherwise: Expr

    def evaluate(self, env: Env) -> Any:
        value = self.condition.evaluate(env)
        chosen = bool(value) if not isinstance(value, str) else len(value) > 0
        return (self.then if chosen else self.otherwise).evaluate(env)


@dataclass(frozen=True)
class Assign(Expr):
    """``:=`` creates, ``=`` assigns an existing entry, ``+= -= *= /=`` update a number (or append text)."""

    name: str
    op: str
    value: Expr

    def evaluate(self, env: Env) -> Any:
        bb = env.blackboard
        entry = bb.entry(self.name)
        if entry is None:
            if self.op != ":=":
                raise TreeRuntimeError(f"script: blackboard entry {self.name} does not exist yet; use := to create it")
            entry = bb.create_entry(self.name)
        value = self.value.evaluate(env)
        current = entry.value
        if self.op in (":=", "="):
            new = _convert_for_entry(current, value, env, self.name)
        else:
            if current is EMPTY:
                raise TreeRuntimeError(f"script: {self.name} {self.op} ... needs {self.name} to have a value")
            new = arithmetic(self.op[0], current, value)
            if isinstance(current, int) and not isinstance(current, bool) and isinstance(new, float):
                new = int(new) if new.is_integer() else new
        entry.value = new
        entry.sequence_id += 1
        return new


def _convert_for_entry(current: Any, value: Any, env: Env, name: str) -> Any:
    """BT.CPP keeps an entry's type after its first value: a number entry converts a string."""
    if current is EMPTY or current is None:
        return value
    if is_number(current) and not isinstance(current, bool) and isinstance(value, str):
        number = string_to_number(value, env)
        return int(number) if isinstance(current, int) and number.is_integer() else number
    if isinstance(current, int) and not isinstance(current, bool) and isinstance(value, float):
        return int(value) if value.is_integer() else value
    return value


@dataclass(frozen=True)
class Program:
    """Statements separated by ``;``; evaluating it returns the last statement's value."""

    source: str
    statements: tuple[Expr, ...]

    def run(self, blackboard: Blackboard, enums: Mapping[str, int]) -> Any:
        env = Env(blackboard, enums)
        result: Any = None
        for statement in self.statements:
            result = statement.evaluate(env)
        return result

    def truth(self, blackboard: Blackboard, enums: Mapping[str, int]) -> bool:
        result = self.run(blackboard, enums)
        if result is None:
            raise TreeRuntimeError(f"script {self.source!r} is empty, it has no true/false value")
        return truthy(result)
