"""Recognising the program a client sends to port 30003 as ur_rtde 1.6.5's ``rtde_control`` script.

The twin does not interpret URScript. ur_rtde's ``ScriptClient`` sends one fixed program (embedded in
``librtde.so``, with the lines its controller version lacks removed) into which it injects two numbers, the
register offset (0, or 24 with ``FLAG_UPPER_RANGE_REGISTERS``), and, for ``moveJ``/``moveL`` with a path, the
path's ``movej``/``movel`` lines. With those injections taken out, the text must hash to the fingerprint ur_rtde
1.6.5 sends to the twin's controller version; then the twin runs that script's register handshake itself
(:mod:`bt_grasp.sim.twin.script_program`). Anything else is refused with one logged sentence.

The fingerprint was taken from the program the unmodified ur_rtde 1.6.5 wheel uploaded to the twin
(``tests/twin/test_control_script.py`` takes it again from the installed wheel).
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass

#: sha256 of the normalised program ur_rtde 1.6.5 sends to a controller of PolyScope 3.15 (the UR5, CB3)
UR_RTDE_1_6_5_CB3 = "4fa45057283892940bd67fe490517acd7163a41771562a421e66c060737293bc"
FINGERPRINTS = {UR_RTDE_1_6_5_CB3: "ur_rtde 1.6.5 rtde_control (PolyScope 3.x)"}

_OFFSET = re.compile(r"(# (float|int) register offset\n)(\d+)")
_PATH = re.compile(r"(        # inject move path\n)((?:\t[^\n]*\n)*)")
_NAME = re.compile(r"\A\s*def\s+([A-Za-z_][A-Za-z0-9_]{0,63})\s*\(")


@dataclass(frozen=True)
class ControlScript:
    """A recognised control script: its register offset and whether a move path was injected."""

    register_offset: int
    has_path: bool
    flavour: str


def normalise(text: str) -> tuple[str, dict[str, int], bool]:
    """The text with the injected numbers and path lines taken out, the offsets found, and whether a path was."""
    offsets = {m.group(2): int(m.group(3)) for m in _OFFSET.finditer(text)}
    text = _OFFSET.sub(r"\1", text)
    path = _PATH.search(text)
    has_path = bool(path and path.group(2))
    text = _PATH.sub(r"\1", text)
    return text, offsets, has_path


def fingerprint(text: str) -> str:
    return hashlib.sha256(normalise(text)[0].encode()).hexdigest()


def program_name(text: str) -> str:
    """The name of the program's first ``def`` (for log sentences), or ``"(unnamed)"``."""
    match = _NAME.match(text)
    return match.group(1) if match else "(unnamed)"


def recognise(text: str) -> ControlScript | str:
    """The script's handshake parameters, or one sentence saying why the twin will not run it."""
    normal, offsets, has_path = normalise(text)
    flavour = FINGERPRINTS.get(hashlib.sha256(normal.encode()).hexdigest())
    if flavour is None:
        return (f"the twin runs only ur_rtde 1.6.5's control script for its controller; a {len(text)}-byte "
                f"program '{program_name(text)}' that is not it was not run")
    if offsets.get("float") != offsets.get("int") or offsets.get("int") not in (0, 24):
        return f"the control script's register offsets {offsets} are not 0 or 24 (both alike); it was not run"
    return ControlScript(register_offset=offsets["int"], has_path=has_path, flavour=flavour)
