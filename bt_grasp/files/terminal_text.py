"""Text from files and peers made safe to print on a terminal: control characters shown, never obeyed.

A log's node name, a viewer's message echoed in a live server's error, a file name quoted in an error sentence
can hold terminal control sequences: ``ESC [ 2 J`` clears the screen, ``ESC ] 0 ; ... ESC \\`` retitles the
window, an OSC 8 sequence makes a hidden link, U+202E reverses what follows. Rich markup escaping does not stop
them (Rich passes ESC through), and neither does click when the output is a terminal. :func:`shown` writes each
such character as a visible escape (``\\x1b``, ``\\u202e``); tabs and, unless asked, newlines are kept.
"""

from __future__ import annotations

import re

from bt_grasp.files.json_types import JsonValue

#: C0 controls but tab and newline, DEL, C1 controls, and the bidirectional overrides and isolates
_UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069]")
_UNSAFE_WITH_NEWLINES = re.compile("[\x00-\x08\x0a-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069]")
#: the same characters as JSON writes them (``\\u001b``): a raw message holds them only so
_JSON_ESCAPE = re.compile(r"\\u(00[01][0-9a-fA-F]|007[fF]|00[89][0-9a-fA-F]|061[cC]|200[eEfF]|202[a-eA-E]|206[6-9])")


def _escape(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def shown(text: str, *, newlines: bool = True) -> str:
    """``text`` with every terminal control character written as a visible escape; ``newlines=False`` escapes
    line breaks too (a one-line sentence)."""
    pattern = _UNSAFE if newlines else _UNSAFE_WITH_NEWLINES
    return pattern.sub(_escape, text) if pattern.search(text) else text


def may_hold_controls(raw_json: str) -> bool:
    """Whether a JSON text may decode to strings with control characters (raw ones are not valid JSON): the fast
    test before walking a decoded message."""
    return _JSON_ESCAPE.search(raw_json) is not None


def shown_deep(value: JsonValue) -> JsonValue:
    """``value`` (decoded JSON) with :func:`shown` applied to every string in it, keys included."""
    if isinstance(value, str):
        return shown(value)
    if isinstance(value, list):
        return [shown_deep(v) for v in value]
    if isinstance(value, dict):
        return {shown(k) if isinstance(k, str) else k: shown_deep(v) for k, v in value.items()}
    return value
