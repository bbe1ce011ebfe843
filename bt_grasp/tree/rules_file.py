"""BehaviorTree.CPP's substitution-rule file, read as ``BehaviorTreeFactory::loadSubstitutionRuleFromJSON`` (4.10)
reads it, and checked strictly: a file from a user is hostile.

The format (BT.CPP's tutorial 11, "Mock testing")::

    {
      "TestNodeConfigs": {
        "NavFails": {"return_status": "FAILURE", "async_delay": 200, "failure_script": "error := 204"},
        "Counted":  {"return_status_script": "n += 1; n > 2 ? SUCCESS : FAILURE"}
      },
      "SubstitutionRules": {
        "ComputePathToPose": "NavFails",        a node's name or type (registration ID) ...
        "recovery/Clear*": "AlwaysSuccess"       ... or a wildcard over its full path; the value is a
      }                                          TestNodeConfig's name or a registered node type
    }

A TestNodeConfig has ``return_status`` (RUNNING, SUCCESS, FAILURE or SKIPPED) or ``return_status_script`` (a
script whose value is one of those, by name or number; it takes precedence), and may have ``async_delay`` (ms:
RUNNING until that much time passed, here simulated time), ``success_script``, ``failure_script`` and
``post_script``. ``TestNodeConfigs`` may be left out.

Read with at most :data:`MAX_RULES_BYTES` bytes; nested at most :data:`MAX_DEPTH` deep. Every problem is one
sentence naming the file, the line and the key (:class:`InputError`, exit 2). bt_grasp is stricter than BT.CPP,
which ignores keys it does not know (a typo such as ``retrun_status`` would silently change a test), keeps the
last of two equal keys, and reads a negative or fractional delay as a whole number of ms: each is refused here.
"""

from __future__ import annotations

import bisect
import json
import re
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.errors import InputError, did_you_mean
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.tree.exceptions import ScriptSyntaxError
from bt_grasp.tree.node import BtStatus
from bt_grasp.tree.scripting import Program, parse_script

#: a rule file is a few hundred lines at most; this is generous
MAX_RULES_BYTES = 1 << 20
#: objects within objects: the format needs 3
MAX_DEPTH = 8
#: rules (and configs) a file may hold: each node of a tree is matched against every rule
MAX_RULES = 10_000
#: the longest delay a config may ask for: BT.CPP reads it as an ``int`` of milliseconds
MAX_DELAY_MS = (1 << 31) - 1

TOP_KEYS = ("TestNodeConfigs", "SubstitutionRules")
CONFIG_KEYS = ("return_status", "return_status_script", "async_delay", "success_script", "failure_script",
               "post_script")
#: the statuses ``return_status`` may name (BT.CPP's ``convertFromString<NodeStatus>``; IDLE is refused by its
#: TestNode)
RETURN_STATUSES = ("RUNNING", "SUCCESS", "FAILURE", "SKIPPED")


@dataclass(frozen=True)
class TestNodeConfig:
    """BT.CPP's ``TestNodeConfig``: what a TestNode does (see :mod:`bt_grasp.tree.test_node`)."""

    __test__ = False  # not a pytest test class

    name: str
    return_status: BtStatus = BtStatus.SUCCESS
    return_status_script: Program | None = None
    async_delay_ms: int = 0
    success_script: Program | None = None
    failure_script: Program | None = None
    post_script: Program | None = None
    where: str = ""  # file:line of its definition


@dataclass(frozen=True)
class RuleEntry:
    """One ``SubstitutionRules`` entry: ``key`` (a name, a type or a path pattern) -> ``target``, which is a
    TestNodeConfig (``config``) or, when no config has that name, a registered node type."""

    key: str
    target: str
    config: TestNodeConfig | None
    line: int


@dataclass(frozen=True)
class RuleFile:
    """A checked substitution-rule file: its rules in file order (the order bt_grasp applies them in)."""

    source: str
    rules: tuple[RuleEntry, ...]
    configs: tuple[TestNodeConfig, ...]

    def where(self, rule: RuleEntry) -> str:
        return f"{self.source}:{rule.line}"


# ---------------------------------------------------------------------------------------------------- JSON
@dataclass(frozen=True)
class Located:
    """A JSON value (text, a number, true/false/null, a :class:`JsonObject` or a :class:`JsonArray`) and the line
    it starts on."""

    value: object
    line: int


@dataclass(frozen=True)
class JsonObject:
    """An object's members in file order: (key, the key's line, value)."""

    members: tuple[tuple[str, int, Located], ...]


@dataclass(frozen=True)
class JsonArray:
    items: tuple[Located, ...]


_NUMBER = re.compile(r"-?(?:0|[1-9][0-9]*)(\.[0-9]+)?([eE][-+]?[0-9]+)?")
_SPACE = re.compile(r"[ \t\n\r]*")
_LITERALS = {"true": True, "false": False, "null": None}


class _Reader:
    """A JSON reader that keeps each value's line: the structure is walked here, strings are decoded by the
    standard library's own scanner (escapes, surrogates, control characters refused)."""

    def __init__(self, text: str, source: str) -> None:
        self.text = text
        self.source = source
        self.pos = 0
        self._strings = json.JSONDecoder(strict=True)
        self._newlines = [i for i, char in enumerate(text) if char == "\n"]  # once: a line is then a bisection

    def line(self, pos: int | None = None) -> int:
        return bisect.bisect_left(self._newlines, self.pos if pos is None else pos) + 1

    def fail(self, problem: str, pos: int | None = None) -> InputError:
        return InputError(self.source, f"not valid JSON: {problem}", where=self.line(pos))

    def skip(self) -> None:
        match = _SPACE.match(self.text, self.pos)
        assert match is not None
        self.pos = match.end()

    def document(self) -> Located:
        self.skip()
        value = self.value(0)
        self.skip()
        if self.pos != len(self.text):
            raise self.fail("text after the end of the object")
        return value

    def value(self, depth: int) -> Located:
        if depth > MAX_DEPTH:
            raise self.fail(f"nested deeper than {MAX_DEPTH} levels")
        line, char = self.line(), self.text[self.pos: self.pos + 1]
        if char == "{":
            return Located(JsonObject(self.object(depth)), line)
        if char == "[":
            return Located(JsonArray(self.array(depth)), line)
        if char == '"':
            return Located(self.string(), line)
        match = _NUMBER.match(self.text, self.pos)
        if match and match.end() > self.pos:
            self.pos = match.end()
            text = match.group()
            if len(text) > 40:  # Python refuses to read integers of thousands of digits; no rule needs one
                raise self.fail(f"a number of {len(text)} characters")
            return Located(float(text) if match.group(1) or match.group(2) else int(text), line)
        for word, literal in _LITERALS.items():
            if self.text.startswith(word, self.pos):
                self.pos += len(word)
                return Located(literal, line)
        raise self.fail(f"unexpected {char!r}" if char else "the text ends early")

    def string(self) -> str:
        try:  # at a '"': the standard decoder reads exactly this string
            text, self.pos = self._strings.raw_decode(self.text, self.pos)
        except json.JSONDecodeError as exc:
            problem = "a control character inside text" if exc.msg.startswith("Invalid control") else exc.msg
            raise self.fail(problem, exc.pos) from None
        if not isinstance(text, str):  # pragma: no cover - a value starting with '"' is a string
            raise self.fail("expected text")
        return text

    def object(self, depth: int) -> tuple[tuple[str, int, Located], ...]:
        self.pos += 1
        items: list[tuple[str, int, Located]] = []
        seen: dict[str, int] = {}
        self.skip()
        if self.text.startswith("}", self.pos):
            self.pos += 1
            return ()
        while True:
            self.skip()
            if not self.text.startswith('"', self.pos):
                raise self.fail("expected a key in double quotes")
            key_line = self.line()
            key = self.string()
            if key in seen:
                raise InputError(self.source, f"the key '{key}' is given twice (first at line {seen[key]}); BT.CPP "
                                 "would keep the last silently", where=key_line)
            seen[key] = key_line
            self.skip()
            if not self.text.startswith(":", self.pos):
                raise self.fail("expected ':' after a key")
            self.pos += 1
            self.skip()
            items.append((key, key_line, self.value(depth + 1)))
            self.skip()
            if self.text.startswith(",", self.pos):
                self.pos += 1
                continue
            if self.text.startswith("}", self.pos):
                self.pos += 1
                return tuple(items)
            raise self.fail("expected ',' or '}'")

    def array(self, depth: int) -> tuple[Located, ...]:
        self.pos += 1
        items: list[Located] = []
        self.skip()
        if self.text.startswith("]", self.pos):
            self.pos += 1
            return ()
        while True:
            self.skip()
            items.append(self.value(depth + 1))
            self.skip()
            if self.text.startswith(",", self.pos):
                self.pos += 1
                continue
            if self.text.startswith("]", self.pos):
                self.pos += 1
                return tuple(items)
            raise self.fail("expected ',' or ']'")


def _kind(value: object) -> str:
    if isinstance(value, JsonObject):
        return "an object"
    if isinstance(value, JsonArray):
        return "a list"
    if isinstance(value, bool):
        return "true or false"
    if value is None:
        return "null"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    return f"the text {json.dumps(value)[:60]}"


# ---------------------------------------------------------------------------------------------------- rules
def _members(source: str, located: Located, what: str) -> tuple[tuple[str, int, Located], ...]:
    value = located.value
    if not isinstance(value, JsonObject):
        raise InputError(source, f"{what} must be a JSON object, got {_kind(value)}", where=located.line)
    return value.members


def _text(source: str, located: Located, what: str) -> str:
    if not isinstance(located.value, str):
        raise InputError(source, f"{what} must be text in double quotes, got {_kind(located.value)}",
                         where=located.line)
    return located.value


def _script(source: str, located: Located, what: str) -> Program:
    text = _text(source, located, what)
    try:
        return parse_script(text)
    except ScriptSyntaxError as exc:
        raise InputError(source, f"{what}: {exc}", where=located.line) from None


def _config(source: str, name: str, line: int, located: Located) -> TestNodeConfig:
    what = f"TestNodeConfig '{name}'"
    fields: dict[str, tuple[int, Located]] = {}
    for key, key_line, value in _members(source, located, what):
        if key not in CONFIG_KEYS:
            raise InputError(source, f"{what} has an unknown key '{key}' (its keys: {', '.join(CONFIG_KEYS)})"
                             f"{did_you_mean(key, CONFIG_KEYS)}", where=key_line)
        fields[key] = (key_line, value)
    if "return_status" not in fields and "return_status_script" not in fields:
        raise InputError(source, f"{what} must contain return_status or return_status_script", where=line)
    status = BtStatus.SUCCESS
    if "return_status" in fields:
        text = _text(source, fields["return_status"][1], f"{what}: return_status")
        statuses = (*RETURN_STATUSES, "IDLE") if "return_status_script" in fields else RETURN_STATUSES
        if text not in statuses:
            raise InputError(source, f"{what}: return_status '{text}' is not one of {', '.join(RETURN_STATUSES)}"
                             f"{did_you_mean(text, RETURN_STATUSES)}", where=fields["return_status"][0])
        status = BtStatus(text)
    delay = 0
    if "async_delay" in fields:
        given = fields["async_delay"][1].value
        if isinstance(given, bool) or not isinstance(given, int) or not 0 <= given <= MAX_DELAY_MS:
            raise InputError(source, f"{what}: async_delay must be a whole number of milliseconds from 0 to "
                             f"{MAX_DELAY_MS}, got {_kind(given)}", where=fields["async_delay"][0])
        delay = given
    scripts = {key: _script(source, fields[key][1], f"{what}: {key}")
               for key in ("return_status_script", "success_script", "failure_script", "post_script")
               if key in fields}
    return TestNodeConfig(name, status, scripts.get("return_status_script"), delay, scripts.get("success_script"),
                          scripts.get("failure_script"), scripts.get("post_script"), f"{source}:{line}")


def parse_rules_text(text: str, source: str) -> RuleFile:
    """Check a rule file's text (see the module); :class:`InputError` at its line for any problem."""
    top = _Reader(text, source).document()
    sections: dict[str, tuple[int, Located]] = {key: (line, value) for key, line, value in _members(source, top,
                                                                                                   "the file")}
    for key in sections:
        if key not in TOP_KEYS:
            raise InputError(source, f"unknown key '{key}' (a substitution-rule file has TestNodeConfigs and "
                             f"SubstitutionRules){did_you_mean(key, TOP_KEYS)}", where=sections[key][0])
    if "SubstitutionRules" not in sections:
        raise InputError(source, "has no SubstitutionRules (BT.CPP requires them)", where=top.line)
    configs: dict[str, TestNodeConfig] = {}
    if "TestNodeConfigs" in sections:
        for name, line, value in _members(source, sections["TestNodeConfigs"][1], "TestNodeConfigs"):
            if not name:
                raise InputError(source, "a TestNodeConfig has an empty name", where=line)
            configs[name] = _config(source, name, line, value)
    rules = []
    members = _members(source, sections["SubstitutionRules"][1], "SubstitutionRules")
    if len(members) > MAX_RULES or len(configs) > MAX_RULES:
        raise InputError(source, f"holds more than {MAX_RULES:,} rules or TestNodeConfigs", where=top.line)
    for key, line, value in members:
        target = _text(source, value, f"the rule '{key}'")
        if not key:
            raise InputError(source, "a rule has an empty key (a node's name, type or path pattern)", where=line)
        if not target:
            raise InputError(source, f"the rule '{key}' names nothing (a TestNodeConfig or a node type)", where=line)
        rules.append(RuleEntry(key, target, configs.get(target), line))
    return RuleFile(source, tuple(rules), tuple(configs.values()))


def read_rules_file(path: str | Path) -> RuleFile:
    """Read and check a substitution-rule file (bounded read; UTF-8)."""
    data = read_user_file(path, MAX_RULES_BYTES)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"is not UTF-8 text (byte {exc.start})") from None
    return parse_rules_text(text.removeprefix("\ufeff"), str(path))
