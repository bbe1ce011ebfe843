"""The evaluated form of a BT.CPP script (BT.CPP ``scripting/operators.hpp``), with BT.CPP's value rules.

* An integer literal is an integer; every operator's result is a real: ``6 / 3`` is 2.0, ``3 * 2`` is 6.0,
  ``-2`` is -2.0, ``1 < 2`` is 1.0 (see :mod:`bt_grasp.tree.values`).
* ``&&`` and ``||`` evaluate both sides; their operands must be castable to bool.
* ``..`` joins a string with a string or a number (a real renders with six decimals).
* Assignment: ``:=`` creates the entry, ``=`` needs it to exist; the first value of an untyped entry is
  stored as it is, later values are converted to the entry's type (a number entry given a numeric string
  becomes a real; an entry declared by a typed port converts the string to that type). A compound
  assignment (``+= -= *= /=``) computes in reals and converts back to the destination's type, so
  ``n := 6; n /= 2`` keeps the integer 3 and ``n := 5; n /= 2`` is an error.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from bt_grasp.tree.blackboard import EMPTY, Blackboard
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.values import (
    EPSILON,
    convert_text,
    copy_into,
    is_number,
    is_scalar,
    to_bool,
    to_int,
    to_real,
    to_text,
    type_name,
)


@dataclass(frozen=True)
class Env:
    """What a script sees: the node's blackboard and the registry's scripting enums."""

    blackboard: Blackboard
    enums: Mapping[str, int]


class Expr:
    def evaluate(self, env: Env) -> object:
        raise NotImplementedError


def _not_init(side: str, op: str) -> TreeRuntimeError:
    return TreeRuntimeError(f"The {side} operand of the operator [{op}] is not initialized")


@dataclass(frozen=True)
class Literal(Expr):
    value: object

    def evaluate(self, env: Env) -> object:
        return self.value


@dataclass(frozen=True)
class Name(Expr):
    """An identifier: a scripting enum (read as a real) when registered, otherwise a blackboard entry."""

    name: str

    def evaluate(self, env: Env) -> object:
        if self.name in env.enums:
            return float(env.enums[self.name])
        entry = env.blackboard.entry(self.name)
        if entry is None:
            raise TreeRuntimeError(f"Variable not found: {self.name}")
        return entry.value  # may be EMPTY: operators report it


@dataclass(frozen=True)
class Unary(Expr):
    op: str  # "-", "!", "~"
    operand: Expr

    def evaluate(self, env: Env) -> object:
        value = self.operand.evaluate(env)
        if is_number(value):
            real = float(value)
            if self.op == "-":
                return -real
            if self.op == "!":
                return 0.0 if real != 0.0 else 1.0
            if not -(2.0**63) <= real < 2.0**63:
                raise TreeRuntimeError("Number out of range for bitwise operation")
            return float(~int(real))
        if isinstance(value, str):
            raise TreeRuntimeError("Invalid operator for std::string")
        raise TreeRuntimeError("ExprUnaryArithmetic: undefined")


_ARITH: dict[str, Callable[[float, float], float]] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": lambda a, b: _divide(a, b),
}
_BITS: dict[str, Callable[[int, int], int]] = {
    "&": lambda a, b: a & b,
    "|": lambda a, b: a | b,
    "^": lambda a, b: a ^ b,
}


def _divide(lhs: float, rhs: float) -> float:
    """IEEE division, as C++ does it (Python raises on a zero divisor)."""
    if rhs == 0.0:
        if lhs == 0.0 or math.isnan(lhs):
            return math.nan
        return math.copysign(math.inf, lhs) * math.copysign(1.0, rhs)
    return lhs / rhs


def arithmetic(op: str, lhs: object, rhs: object) -> object:
    """BT.CPP ``ExprBinaryArithmetic::evaluate`` on two values."""
    if lhs is EMPTY:
        raise _not_init("left", op)
    if rhs is EMPTY:
        raise _not_init("right", op)
    if is_number(lhs) and is_number(rhs):
        if op in _ARITH:
            return _ARITH[op](float(lhs), float(rhs))
        if op in _BITS:
            try:
                return float(_BITS[op](to_int(lhs), to_int(rhs)))
            except TreeRuntimeError:
                raise TreeRuntimeError(
                    "Binary operators are not allowed if one of the operands is not an integer"
                ) from None
        if op in ("&&", "||"):
            try:
                left, right = to_bool(lhs), to_bool(rhs)
            except TreeRuntimeError:
                raise TreeRuntimeError(
                    "Logic operators are not allowed if one of the operands is not castable to bool"
                ) from None
            return float(left and right) if op == "&&" else float(left or right)
        raise TreeRuntimeError("Operation not permitted")  # ".." between two numbers
    if isinstance(lhs, str) and isinstance(rhs, str) and op == "+":
        return lhs + rhs
    texts = (isinstance(lhs, str) and (isinstance(rhs, str) or is_number(rhs))) or (
        is_number(lhs) and isinstance(rhs, str)
    )
    if op == ".." and texts:
        return to_text(lhs) + to_text(rhs)
    raise TreeRuntimeError("Operation not permitted")


@dataclass(frozen=True)
class Binary(Expr):
    op: str
    lhs: Expr
    rhs: Expr

    def evaluate(self, env: Env) -> object:
        return arithmetic(self.op, self.lhs.evaluate(env), self.rhs.evaluate(env))


def _holds_real(op: str, lhs: float, rhs: float) -> bool:
    """Reals compare within BT.CPP's epsilon for equality."""
    if op == "==":
        return abs(lhs - rhs) <= EPSILON
    if op == "!=":
        return not abs(lhs - rhs) <= EPSILON
    return {"<": lhs < rhs, ">": lhs > rhs, "<=": lhs <= rhs, ">=": lhs >= rhs}[op]


def _holds_bytes(op: str, lhs: bytes, rhs: bytes) -> bool:
    """Strings compare as their bytes."""
    return {"==": lhs == rhs, "!=": lhs != rhs, "<": lhs < rhs, ">": lhs > rhs, "<=": lhs <= rhs,
            ">=": lhs >= rhs}[op]


def compare(op: str, lhs: object, rhs: object, enums: Mapping[str, int]) -> bool:
    """One comparison of BT.CPP ``ExprComparison``: numbers as reals, strings as bytes, a string and a
    number by reading the string as a number (``true``, ``false`` and enum names included)."""
    if lhs is EMPTY:
        raise _not_init("left", op)
    if rhs is EMPTY:
        raise _not_init("right", op)
    if is_number(lhs) and is_number(rhs):
        return _holds_real(op, float(lhs), float(rhs))
    if isinstance(lhs, str) and isinstance(rhs, str):
        return _holds_bytes(op, lhs.encode(), rhs.encode())
    if isinstance(lhs, str) and is_number(rhs):
        return _holds_real(op, to_real(lhs, enums), float(rhs))
    if is_number(lhs) and isinstance(rhs, str):
        return _holds_real(op, float(lhs), to_real(rhs, enums))
    raise TreeRuntimeError(
        f"Can't mix different types in Comparison. Left operand [{type_name(lhs)}] right operand [{type_name(rhs)}]"
    )


@dataclass(frozen=True)
class Compare(Expr):
    """A chained comparison ``a < b < c`` (each adjacent pair); 1.0 when all hold, else 0.0."""

    operands: tuple[Expr, ...]
    ops: tuple[str, ...]

    def evaluate(self, env: Env) -> object:
        lhs = self.operands[0].evaluate(env)
        for op, operand in zip(self.ops, self.operands[1:], strict=True):
            rhs = operand.evaluate(env)
            if not compare(op, lhs, rhs, env.enums):
                return 0.0
            lhs = rhs
        return 1.0


@dataclass(frozen=True)
class Ternary(Expr):
    """``cond ? a : b``: the condition is read as a real (a string must be numeric, as in BT.CPP 4.10)."""

    condition: Expr
    then: Expr
    otherwise: Expr

    def evaluate(self, env: Env) -> object:
        value = self.condition.evaluate(env)
        if value is EMPTY:
            raise TreeRuntimeError("Any::cast failed because it is empty")
        chosen = to_real(value) != 0.0
        return (self.then if chosen else self.otherwise).evaluate(env)


@dataclass(frozen=True)
class Assign(Expr):
    """``:=`` creates, ``=`` assigns an existing entry, ``+= -= *= /=`` update it (see the module doc)."""

    target: Expr
    op: str
    value: Expr

    def evaluate(self, env: Env) -> object:
        if not isinstance(self.target, Name):
            raise TreeRuntimeError("Assignment left operand not a blackboard entry")
        key = self.target.name
        bb = env.blackboard
        entry = bb.entry(key)
        if entry is None:
            if self.op != ":=":
                raise TreeRuntimeError(
                    f"The blackboard entry [{key}] doesn't exist, yet. If you want to create a new one, "
                    "use the operator [:=] instead of [=]"
                )
            entry = bb.create_entry(key)
        value = self.value.evaluate(env)
        if value is EMPTY:
            raise _not_init("right", self.op)
        current = entry.value
        if self.op in (":=", "="):
            new = self._assigned(key, entry.declared, current, value, env)
        else:
            if current is EMPTY:
                raise _not_init("left", self.op)
            new = self._updated(current, value)
        entry.value = new
        entry.sequence_id += 1
        return new

    def _assigned(self, key: str, declared: type | None, current: object, value: object, env: Env) -> object:
        if current is EMPTY and declared is None:
            return value
        if isinstance(value, str) and not isinstance(current, str):
            if declared is not None and declared is not object:
                return convert_text(value, declared)
            if is_number(current):
                return to_real(value, env.enums)
            raise TreeRuntimeError(
                f"Error assigning a value to entry [{key}] with type [{type_name(current)}]. "
                "The right operand is a string, can't convert to it"
            )
        if current is EMPTY:
            return value
        try:
            return copy_into(value, current)
        except TreeRuntimeError as exc:
            raise TreeRuntimeError(
                f"Error assigning a value to entry [{key}] with type [{type_name(current)}]. "
                f"The right operand has type [{type_name(value)}] and can't be converted ({exc})"
            ) from None

    def _updated(self, current: object, value: object) -> object:
        temp = current
        if is_number(value):
            if not is_number(current):
                raise TreeRuntimeError("This Assignment operator can't be used with a non-numeric type")
            temp = _ARITH[self.op[0]](float(current), float(value))
        elif isinstance(value, str):
            if self.op != "+=":
                raise TreeRuntimeError("Operator not supported for strings")
            temp = to_text(current) + value
        return copy_into(temp, current)


@dataclass(frozen=True)
class Program:
    """Statements (separated by ``;`` or simply following each other); evaluating it returns the last
    statement's value."""

    source: str
    statements: tuple[Expr, ...]

    def run(self, blackboard: Blackboard, enums: Mapping[str, int]) -> object:
        env = Env(blackboard, enums)
        result: object = None
        try:
            for statement in self.statements:
                result = statement.evaluate(env)
        except TreeRuntimeError as exc:
            raise TreeRuntimeError(f"Error in script [{self.source}]: {exc}") from None
        return result

    def assigned_names(self) -> frozenset[str]:
        """Every blackboard entry the program assigns to (for load-time checks)."""
        names: set[str] = set()
        pending: list[object] = list(self.statements)
        while pending:
            expr = pending.pop()
            if isinstance(expr, Assign) and isinstance(expr.target, Name):
                names.add(expr.target.name)
            for value in vars(expr).values():
                if isinstance(value, Expr):
                    pending.append(value)
                elif isinstance(value, tuple):
                    pending.extend(v for v in value if isinstance(v, Expr))
        return frozenset(names)

    def truth(self, blackboard: Blackboard, enums: Mapping[str, int]) -> bool:
        """The program's value as BT.CPP's ``cast<bool>`` reads it (ScriptCondition, ``_skipIf`` ...)."""
        result = self.run(blackboard, enums)
        try:
            if result is EMPTY:
                raise TreeRuntimeError("Any::cast failed because it is empty")
            return to_bool(result)
        except TreeRuntimeError as exc:
            raise TreeRuntimeError(f"script [{self.source}]: {exc}") from None


__all__ = ["Env", "Expr", "Program", "arithmetic", "compare", "is_scalar"]
