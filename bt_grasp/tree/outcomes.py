"""What a dry run's stand-ins are told to do, call by call: ``--outcome`` and ``--output-port`` values.

``--outcome NAME=OUTCOME[,OUTCOME...]`` gives a stand-in one outcome per call (per attempt: each time it starts
from IDLE), the last repeating::

    ComputePath=failure,failure,success     fails twice, then succeeds every time
    FollowPath=running:3                    RUNNING for 3 ticks, then SUCCESS, every call
    Grasp=running:2:failure:SLIPPED         RUNNING for 2 ticks, then FAILURE with SLIPPED

``--output-port NAME.PORT=VALUE[,VALUE...]`` is the value the stand-in writes to its output port PORT when a call
completes, call by call in the same way (the text is converted to the port's type).

NAME is matched as BehaviorTree.CPP matches a substitution rule's key (``BehaviorTreeFactory::instantiateTreeNode``):
it equals the node's type (registration ID) or its name, or it matches the node's full path with the wildcards
``*`` (any run of characters) and ``?`` (one character), BT.CPP's ``wildcards_match``. Each node counts its own
calls.
"""

from __future__ import annotations

import enum
import functools
from dataclasses import dataclass

from bt_grasp.errors import InputError

OUTCOME_SYNTAX = "NAME=OUTCOME[,OUTCOME...], each success, failure[:REASON] or running:N[:failure[:REASON]]"
OUTPUT_SYNTAX = "NAME.PORT=VALUE[,VALUE...]"


def wildcards_match(text: str, pattern: str) -> bool:
    """BT.CPP 4.10's ``wildcards_match``: ``*`` matches any run of characters (the empty one too), ``?`` one
    character, anything else itself (no ``[...]`` classes, no escapes)."""
    return _match(text, pattern)


@functools.lru_cache(maxsize=4096)
def _match(text: str, pattern: str) -> bool:
    # iterative two-pointer matching with backtracking to the last '*': linear in practice, no recursion depth
    t = p = 0
    star, mark = -1, 0
    while t < len(text):
        if p < len(pattern) and (pattern[p] == "?" or pattern[p] == text[t]):
            t, p = t + 1, p + 1
        elif p < len(pattern) and pattern[p] == "*":
            star, mark, p = p, t, p + 1
        elif star >= 0:
            p, mark = star + 1, mark + 1
            t = mark
        else:
            return False
    while p < len(pattern) and pattern[p] == "*":
        p += 1
    return p == len(pattern)


def names_node(key: str, node_type: str, name: str, path: str) -> bool:
    """BT.CPP's rule: ``key`` equals the node's type or name, or wildcard-matches its full path."""
    return key in (node_type, name) or wildcards_match(path, key)


def has_wildcard(key: str) -> bool:
    return "*" in key or "?" in key


class OutcomeKind(enum.Enum):
    SUCCESS = "success"
    FAILURE = "failure"


@dataclass(frozen=True)
class Outcome:
    """One call of a stand-in: RUNNING ``running_ticks`` ticks, then SUCCESS, or FAILURE with ``reason`` (None: the
    leaf's first declared reason, or none)."""

    kind: OutcomeKind = OutcomeKind.SUCCESS
    reason: str | None = None
    running_ticks: int = 0


@dataclass(frozen=True)
class OutcomeRule:
    """``target=outcome,outcome,...``: the outcome of each call, the last repeating."""

    target: str
    outcomes: tuple[Outcome, ...]
    text: str

    def matches(self, node_type: str, name: str, path: str) -> bool:
        return names_node(self.target, node_type, name, path)

    def for_call(self, call: int) -> Outcome:
        """The outcome of call ``call`` (from 0)."""
        return self.outcomes[min(call, len(self.outcomes) - 1)]

    @property
    def where(self) -> str:
        return f"--outcome '{self.text}'"


def _one_outcome(text: str, where: str) -> Outcome:
    parts = [p.strip() for p in text.split(":")]
    head = parts[0].lower()
    if head == "success" and len(parts) == 1:
        return Outcome()
    if head == "failure" and len(parts) <= 2:
        return Outcome(OutcomeKind.FAILURE, parts[1] if len(parts) == 2 and parts[1] else None)
    if head == "running" and len(parts) >= 2 and parts[1].isdigit() and parts[1].isascii():
        ticks = int(parts[1])
        if ticks > 1_000_000:
            raise InputError(where, f"running:{ticks} is more than a million ticks")
        if len(parts) == 2 or (len(parts) == 3 and parts[2].lower() == "success"):
            return Outcome(running_ticks=ticks)
        if parts[2].lower() == "failure" and len(parts) <= 4:
            return Outcome(OutcomeKind.FAILURE, parts[3] if len(parts) == 4 and parts[3] else None, ticks)
    raise InputError(where, f"'{text}' is not an outcome: the syntax is {OUTCOME_SYNTAX}")


def parse_outcome(text: str) -> OutcomeRule:
    """One ``--outcome`` value; an :class:`InputError` (one sentence) when it is malformed."""
    where = f"--outcome '{text}'"
    target, sep, value = (part.strip() for part in text.partition("="))
    if not sep or not target or not value:
        raise InputError(where, f"is not {OUTCOME_SYNTAX}")
    items = [item.strip() for item in value.split(",")]
    if len(items) > 10_000:
        raise InputError(where, "gives more than 10,000 calls")
    if any(not item for item in items):
        raise InputError(where, f"has an empty outcome between commas: the syntax is {OUTCOME_SYNTAX}")
    return OutcomeRule(target, tuple(_one_outcome(item, where) for item in items), text)


@dataclass(frozen=True)
class OutputRule:
    """``target.port=value,value,...``: what a stand-in writes to an output port, call by call (text, converted
    to the port's type when the node is built)."""

    target: str
    port: str
    values: tuple[str, ...]
    text: str

    def matches(self, node_type: str, name: str, path: str) -> bool:
        return names_node(self.target, node_type, name, path)

    def for_call(self, call: int) -> str:
        return self.values[min(call, len(self.values) - 1)]

    @property
    def where(self) -> str:
        return f"--output-port '{self.text}'"


def parse_output(text: str) -> OutputRule:
    """One ``--output-port`` value; an :class:`InputError` when it is malformed."""
    where = f"--output-port '{text}'"
    head, sep, value = text.partition("=")
    target, dot, port = head.strip().rpartition(".")
    if not sep or not dot or not target or not port:
        raise InputError(where, f"is not {OUTPUT_SYNTAX} (e.g. ComputePathToPose.error_code_id=204,0)")
    values = tuple(v.strip() for v in value.split(","))
    if len(values) > 10_000:
        raise InputError(where, "gives more than 10,000 calls")
    return OutputRule(target, port.strip(), values, text)
