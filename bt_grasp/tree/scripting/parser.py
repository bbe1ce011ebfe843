"""BehaviorTree.CPP's script language, parsed with lark (never ``eval``).

Grammar (lowest binding first), as in BT.CPP's ``scripting/operators.hpp``::

    statements   a := 1; b = a + 2          separated by ';'
    assignment   :=  =  +=  -=  *=  /=      left side must be a name
    ternary      cond ? x : y
    logical      &&  ||                     one precedence level, left to right (as BT.CPP)
    comparison   ==  !=  <  >  <=  >=       chains: 1 < x < 3
    concat       ..                         string concatenation
    bitwise      |  ^   then  &
    arithmetic   +  -   then  *  /
    unary        -  !  ~
    atoms        numbers (12, 0x1F, 1.5, 2e3), 'single' or "double" quoted strings, true, false,
                 names (enums first, then blackboard variables; @name is the root blackboard), ( ... )

BT.CPP forbids mixing arithmetic, bitwise and string operators without parentheses; this parser accepts
the mix with the precedence above (every script BT.CPP accepts means the same here).
"""

from __future__ import annotations

import functools

import lark

from bt_grasp.tree.exceptions import ScriptSyntaxError
from bt_grasp.tree.scripting.operators import (
    Assign,
    Binary,
    Compare,
    Expr,
    Literal,
    Name,
    Program,
    Ternary,
    Unary,
)

_GRAMMAR = r"""
start: stmt (";" stmt)*
stmt: expr?

?expr: NAME assign_op cond -> assign
     | cond
!assign_op: ":=" | "=" | "+=" | "-=" | "*=" | "/="

?cond: logic "?" expr ":" logic -> ternary
     | logic

?logic: logic logic_op compare -> binary
      | compare
!logic_op: "&&" | "||"

?compare: concat (cmp_op concat)+ -> compare
        | concat
!cmp_op: "==" | "!=" | "<=" | ">=" | "<" | ">"

?concat: concat concat_op bitor -> binary
       | bitor
!concat_op: ".."

?bitor: bitor bitor_op bitand -> binary
      | bitand
!bitor_op: "|" | "^"

?bitand: bitand bitand_op sum -> binary
       | sum
!bitand_op: "&"

?sum: sum sum_op product -> binary
    | product
!sum_op: "+" | "-"

?product: product product_op unary -> binary
        | unary
!product_op: "*" | "/"

?unary: unary_op unary -> unary
      | atom
!unary_op: "-" | "!" | "~"

?atom: NUMBER -> number
     | STRING -> string
     | NAME -> name
     | "(" expr ")"

NUMBER: /0[xX][0-9a-fA-F]+|[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?/
STRING: /'[^']*'/ | /"[^"]*"/
NAME: /[A-Za-z_@][A-Za-z0-9_]*/

%ignore /[ \t\r\n]+/
"""


@functools.cache
def _parser() -> lark.Lark:
    return lark.Lark(_GRAMMAR, parser="lalr", maybe_placeholders=False)


def _op(tree: lark.Tree) -> str:
    return str(tree.children[0])


def _number(text: str) -> int | float:
    if text[:2] in ("0x", "0X"):
        return int(text, 16)
    if any(c in text for c in ".eE"):
        return float(text)
    return int(text)


def _build(node: lark.Tree | lark.Token) -> Expr:
    if isinstance(node, lark.Token):  # pragma: no cover - every token is wrapped by a rule
        raise ScriptSyntaxError(str(node), "unexpected token")
    kind = node.data
    ch = node.children
    if kind == "number":
        return Literal(_number(str(ch[0])))
    if kind == "string":
        return Literal(str(ch[0])[1:-1])
    if kind == "name":
        text = str(ch[0])
        if text in ("true", "false"):
            return Literal(text == "true")
        return Name(text)
    if kind == "unary":
        return Unary(_op(ch[0]), _build(ch[1]))  # type: ignore[arg-type]
    if kind == "binary":
        return Binary(_op(ch[1]), _build(ch[0]), _build(ch[2]))  # type: ignore[arg-type]
    if kind == "compare":
        operands = tuple(_build(c) for c in ch[0::2])
        ops = tuple(_op(c) for c in ch[1::2])  # type: ignore[arg-type]
        return Compare(operands, ops)
    if kind == "ternary":
        return Ternary(_build(ch[0]), _build(ch[1]), _build(ch[2]))
    if kind == "assign":
        target = str(ch[0])
        if target in ("true", "false"):
            raise ScriptSyntaxError(target, "cannot assign to a boolean literal")
        return Assign(target, _op(ch[1]), _build(ch[2]))  # type: ignore[arg-type]
    raise ScriptSyntaxError(kind, f"unsupported construct {kind}")  # pragma: no cover


@functools.lru_cache(maxsize=2048)
def parse_script(source: str) -> Program:
    """Parse ``source`` into a :class:`Program`; raises :class:`ScriptSyntaxError`."""
    try:
        tree = _parser().parse(source)
    except lark.exceptions.UnexpectedInput as exc:
        column = getattr(exc, "column", None)
        if isinstance(exc, lark.exceptions.UnexpectedEOF):
            problem = "unexpected end of script"
            column = None
        elif isinstance(exc, lark.exceptions.UnexpectedCharacters):
            problem = f"unexpected character {source[exc.pos_in_stream or 0]!r}"
        else:
            token = getattr(exc, "token", None)
            problem = f"unexpected {str(token)!r}" if token is not None and str(token) else "unexpected end"
        raise ScriptSyntaxError(source, problem, column if isinstance(column, int) and column > 0 else None) from None
    statements: list[Expr] = []
    for stmt in tree.children:
        assert isinstance(stmt, lark.Tree)
        for child in stmt.children:
            try:
                statements.append(_build(child))  # type: ignore[arg-type]
            except ScriptSyntaxError as exc:
                raise ScriptSyntaxError(source, exc.problem) from None
    return Program(source, tuple(statements))
