"""Breakpoints: where a running episode pauses by itself.

A breakpoint is written as a spec (``--break SPEC`` on ``bt-grasp run``, repeatable, or from a front end):

==================  ===========================================================================================
``node:NAME``       before node NAME (a name, or a path such as ``pick/Perceive``) starts: the tick holds just
                    before the node's own tick, when the node is not already RUNNING (a new attempt)
``fail``            after a tick in which a leaf returned FAILURE, unless the failure was false by design (a
                    condition asked by a Fallback, or answering "no" without a reason: the failures
                    ``replay --failures`` sets apart; ``bt_grasp.tree.failure_kinds``)
``fail:REASON``     ... such a FAILURE with this reason code (``NO_DETECTION``, ``IK_UNREACHABLE``, ...)
``fail:all``        after a tick in which a leaf returned FAILURE, those false by design included
``bb:KEY``          after a tick that changed blackboard entry KEY (of the main tree; its value differs)
``tick:N``          after tick N (``tick:0``: before the first tick)
``time:S``          at the first tick boundary at or after S simulated seconds
==================  ===========================================================================================

A bad spec is an :class:`bt_grasp.errors.InputError` naming ``--break`` and the spec.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from bt_grasp.errors import InputError

SOURCE = "--break"
SYNTAX = "node:NAME, fail, fail:REASON, fail:all, bb:KEY, tick:N or time:S"
#: ``fail:all``'s target: every leaf FAILURE (reason codes are upper case, so no reason is named this)
EVERY_FAILURE = "all"
#: a run holds at most this many breakpoints (20,000 in one message stalled the tick loop for minutes)
MAX_BREAKPOINTS = 100
#: the longest spec (a node's path, a reason, an entry's name)
MAX_SPEC_CHARS = 500


class BreakKind(enum.StrEnum):
    NODE = "node"
    FAILURE = "fail"
    BLACKBOARD = "bb"
    TICK = "tick"
    TIME = "time"


@dataclass(frozen=True)
class Breakpoint:
    """One breakpoint. ``target``: the node (NODE), the reason ('' for any failure not false by design,
    :data:`EVERY_FAILURE` for every one: FAILURE), the entry (BLACKBOARD); ``tick`` for TICK; ``time_s`` for
    TIME."""

    kind: BreakKind
    target: str = ""
    tick: int = 0
    time_s: float = 0.0

    def stops_at(self, reason: str | None, by_design: bool) -> bool:
        """Whether this FAILURE breakpoint stops at a leaf FAILURE with ``reason``."""
        if self.target == EVERY_FAILURE:
            return True
        return not by_design and (not self.target or self.target == reason)

    @property
    def spec(self) -> str:
        """The spec that parses back to this breakpoint."""
        if self.kind is BreakKind.TICK:
            return f"tick:{self.tick}"
        if self.kind is BreakKind.TIME:
            return f"time:{self.time_s:g}"
        if self.kind is BreakKind.FAILURE and not self.target:
            return "fail"
        return f"{self.kind.value}:{self.target}"


def parse_breakpoint(spec: str, source: str = SOURCE) -> Breakpoint:
    """The breakpoint a spec names; InputError (one sentence) on a bad spec."""
    if len(spec) > MAX_SPEC_CHARS:
        raise InputError(source, f"a breakpoint spec is at most {MAX_SPEC_CHARS} characters, got {len(spec)}")
    text = spec.strip()
    head, sep, tail = text.partition(":")
    tail = tail.strip()

    def bad(problem: str) -> InputError:
        return InputError(source, f"{spec!r}: {problem}; expected {SYNTAX}")

    if head == "fail":
        if sep and not tail:
            raise bad("a reason after 'fail:' is empty")
        return Breakpoint(BreakKind.FAILURE, tail)
    if not sep:
        raise bad("no kind before ':'")
    if head in ("node", "bb"):
        if not tail:
            raise bad(f"'{head}:' names nothing")
        return Breakpoint(BreakKind(head), tail)
    if head == "tick":
        try:
            tick = int(tail)
        except ValueError:
            raise bad(f"'{tail}' is not a tick number") from None
        if tick < 0:
            raise bad("a tick is 0 or more")
        if tick >= 2**63:
            raise bad("a tick is below 2^63")
        return Breakpoint(BreakKind.TICK, tick=tick)
    if head == "time":
        try:
            time_s = float(tail)
        except ValueError:
            raise bad(f"'{tail}' is not a number of seconds") from None
        if not math.isfinite(time_s) or time_s < 0:
            raise bad("a time is a finite number of seconds, 0 or more")
        return Breakpoint(BreakKind.TIME, time_s=time_s)
    raise bad(f"unknown kind '{head}'")


def parse_breakpoints(specs: list[str] | tuple[str, ...], source: str = SOURCE) -> tuple[Breakpoint, ...]:
    return tuple(parse_breakpoint(s, source) for s in specs)
