"""BehaviorTree.CPP 4.10's script language: tokenizer and Pratt parser (BT.CPP ``script_tokenizer.cpp`` and
``script_parser.cpp``), never ``eval``.

Binding powers, loosest first (an operator binds its operands more tightly the higher it is)::

    2   :=  =  +=  -=  *=  /=      right side is a whole expression: a := b := 3 is a := (b := 3)
    4   cond ? a : b               "a" is a whole expression, "b" may itself be a ternary
    6   ||
    8   &&
    10  ==  !=  <  >  <=  >=       chains: 1 < x < 3 compares each adjacent pair
    12  |  ^
    14  &
    16  +  -  ..
    18  *  /
    20  prefix - ! ~

Atoms: integers (``12``, ``0x1F``), reals (``1.5``, ``2e3``), 'single-quoted' strings (double quotes are an
error, as in BT.CPP), ``true``/``false`` (the reals 1.0 and 0.0), names (``@name`` is the root blackboard),
parentheses. Statements are separated by ``;`` (a new statement may also simply follow the previous one).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

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

_TWO_CHAR = ("..", "&&", "||", "==", "!=", "<=", ">=", ":=", "+=", "-=", "*=", "/=")
_ONE_CHAR = frozenset("+-*/&|^~!<>=?:();")
_ASSIGN = frozenset({":=", "=", "+=", "-=", "*=", "/="})
_COMPARE = frozenset({"==", "!=", "<", ">", "<=", ">="})
_ASSIGN_BP, _TERNARY_BP, _COMPARE_BP, _PREFIX_BP = 2, 4, 10, 20
_INFIX_BP = {"||": 6, "&&": 8, "|": 12, "^": 12, "&": 14, "+": 16, "-": 16, "..": 16, "*": 18, "/": 18}


@dataclass(frozen=True)
class Token:
    kind: str  # "int", "real", "str", "bool", "name", "op", "error", "end"
    text: str
    pos: int


def _ident_start(c: str) -> bool:
    return c.isascii() and (c.isalpha() or c in "_@")


def _ident_char(c: str) -> bool:
    return c.isascii() and (c.isalnum() or c == "_")


def _number(source: str, i: int) -> tuple[Token, int]:
    start, n = i, len(source)
    error = real = False
    if source[i] == "0" and i + 1 < n and source[i + 1] in "xX":
        i += 2
        if i >= n or source[i] not in "0123456789abcdefABCDEF":
            error = True
        while i < n and source[i] in "0123456789abcdefABCDEF":
            i += 1
        if i < n and (source[i] == "." or _ident_char(source[i])):
            error = True
            while i < n and (_ident_char(source[i]) or source[i] == "."):
                i += 1
    else:
        while i < n and source[i].isdigit():
            i += 1
        if i < n and source[i] == ".":
            if i + 1 < n and source[i + 1] == ".":
                pass  # "1..2" is 1 .. 2
            elif i + 1 < n and source[i + 1].isdigit():
                real = True
                i += 1
                while i < n and source[i].isdigit():
                    i += 1
            else:
                error = True
                i += 1
                while i < n and (_ident_char(source[i]) or source[i] == "."):
                    i += 1
        if not error and i < n and source[i] in "eE":
            real = True
            i += 1
            if i < n and source[i] in "+-":
                i += 1
            if i >= n or not source[i].isdigit():
                error = True
            while i < n and source[i].isdigit():
                i += 1
        if not error and i < n and _ident_start(source[i]):
            error = True
            while i < n and _ident_char(source[i]):
                i += 1
    kind = "error" if error else "real" if real else "int"
    return Token(kind, source[start:i], start), i


def tokenize(source: str) -> list[Token]:
    tokens: list[Token] = []
    i, n = 0, len(source)
    while i < n:
        c = source[i]
        if c in " \t\n\r":
            i += 1
        elif c == "'":
            end = source.find("'", i + 1)
            if end < 0:
                tokens.append(Token("error", source[i:], i))
                i = n
            else:
                tokens.append(Token("str", source[i + 1 : end], i))
                i = end + 1
        elif c.isascii() and c.isdigit():
            token, i = _number(source, i)
            tokens.append(token)
        elif _ident_start(c):
            start = i
            i += 1
            while i < n and _ident_char(source[i]):
                i += 1
            text = source[start:i]
            tokens.append(Token("bool" if text in ("true", "false") else "name", text, start))
        elif source[i : i + 2] in _TWO_CHAR:
            tokens.append(Token("op", source[i : i + 2], i))
            i += 2
        else:
            tokens.append(Token("op" if c in _ONE_CHAR else "error", c, i))
            i += 1
    tokens.append(Token("end", "", n))
    return tokens


class _Parser:
    def __init__(self, source: str) -> None:
        self.source = source
        self.tokens = tokenize(source)
        self.current = 0

    def error(self, problem: str, pos: int) -> ScriptSyntaxError:
        return ScriptSyntaxError(self.source, problem, pos + 1)

    def peek(self) -> Token:
        return self.tokens[self.current]

    def advance(self) -> Token:
        token = self.tokens[self.current]
        if token.kind != "end":
            self.current += 1
        return token

    def expect(self, text: str, problem: str) -> None:
        token = self.peek()
        if token.kind != "op" or token.text != text:
            got = token.text or "end of script"
            raise self.error(f"{problem} (got '{got}')", token.pos)
        self.advance()

    def statements(self) -> list[Expr]:
        found: list[Expr] = []
        while self.peek().kind != "end":
            found.append(self.expression(0))
            while self.peek().kind == "op" and self.peek().text == ";":
                self.advance()
        return found

    def prefix(self) -> Expr:
        token = self.advance()
        kind, text = token.kind, token.text
        if kind == "op" and text in ("-", "!", "~"):
            return Unary(text, self.expression(_PREFIX_BP))
        if kind == "op" and text == "(":
            inner = self.expression(0)
            self.expect(")", "expected ')'")
            return inner
        if kind == "bool":
            return Literal(1.0 if text == "true" else 0.0)
        if kind == "int":
            return Literal(int(text, 16) if text[:2] in ("0x", "0X") else int(text))
        if kind == "real":
            return Literal(float(text))
        if kind == "str":
            return Literal(text)
        if kind == "name":
            return Name(text)
        if kind == "error":
            raise self.error(f"invalid token '{text}'", token.pos)
        got = text or "end of script"
        raise self.error(f"expected an operand (got '{got}')", token.pos)

    @staticmethod
    def binding(token: Token) -> int:
        if token.kind != "op":
            return -1
        if token.text in _ASSIGN:
            return _ASSIGN_BP
        if token.text == "?":
            return _TERNARY_BP
        if token.text in _COMPARE:
            return _COMPARE_BP
        return _INFIX_BP.get(token.text, -1)

    def expression(self, min_bp: int) -> Expr:
        left = self.prefix()
        while True:
            token = self.peek()
            bp = self.binding(token)
            if bp < 0 or bp < min_bp:
                return left
            if token.text in _ASSIGN:
                if not isinstance(left, Name):  # BT.CPP parses it and fails at the first tick
                    raise self.error(f"the left side of '{token.text}' must be a blackboard entry", token.pos)
                self.advance()
                return Assign(left, token.text, self.expression(0))
            if token.text == "?":
                self.advance()
                then = self.expression(0)
                self.expect(":", "expected ':' in ternary expression")
                return Ternary(left, then, self.expression(_TERNARY_BP))
            if token.text in _COMPARE:
                left = self.comparison(left)
                continue
            self.advance()
            left = Binary(token.text, left, self.expression(bp + 1))

    def comparison(self, first: Expr) -> Expr:
        operands, ops = [first], []
        while self.peek().kind == "op" and self.peek().text in _COMPARE:
            ops.append(self.advance().text)
            operands.append(self.expression(_COMPARE_BP + 1))
        return Compare(tuple(operands), tuple(ops))


@functools.lru_cache(maxsize=4096)
def parse_script(source: str) -> Program:
    """Parse ``source`` into a :class:`Program`; raises :class:`ScriptSyntaxError` (an empty script too)."""
    statements = _Parser(source).statements()
    if not statements:
        raise ScriptSyntaxError(source, "the script is empty")
    return Program(source, tuple(statements))
