"""One error hierarchy for bt_grasp.

Expected outcomes (an unreachable pose, no detection) are values, not exceptions. Exceptions are for
broken invariants and for bad input. Every bad-input error carries the file, the place in it (a line or
a key) and the problem, so the command line can print one sentence and exit with code 2.
"""

from __future__ import annotations

import difflib
from pathlib import Path


class BtGraspError(Exception):
    """Base class of every error bt_grasp raises on purpose."""

    #: process exit code the command line uses for this error
    exit_code: int = 1


class InputError(BtGraspError):
    """A file or argument a user wrote is wrong: exit code 2, one sentence naming file, place, problem.

    Args:
        source: the file (or argument name) the problem is in
        problem: what is wrong, as a sentence fragment ("unknown key 'colr'; expected one of ...")
        where: the place inside the file: ``"line 12"``, ``"objects[2].size"``; empty when not known
    """

    exit_code = 2

    def __init__(self, source: str | Path, problem: str, where: str | int | None = None) -> None:
        self.source = str(source)
        self.problem = problem
        if isinstance(where, int):
            where = f"line {where}"
        self.where = where or ""
        super().__init__(self.message)

    @property
    def message(self) -> str:
        place = f":{self.where.removeprefix('line ')}" if self.where.startswith("line ") else ""
        key = f" at {self.where}" if self.where and not place else ""
        return f"{self.source}{place}: {self.problem}{key}"


class ConfigError(InputError):
    """A configuration file (scene, calibration, fault plan, ...) is invalid."""


class LayoutError(ConfigError):
    """A scene whose objects cannot be laid out without overlapping for one seed: the seed's draw, not the file,
    is the problem (another seed may lay them out). A benchmark over many seeds lists such a seed and goes on."""


class TreeFileError(InputError):
    """A behaviour-tree file (XML or YAML) is invalid."""


class LogFileError(InputError):
    """A log file a user asked to read is not a readable bt_grasp MCAP log."""


class RenderDeviceError(BtGraspError):
    """No Vulkan rendering device is available for SAPIEN's renderer."""

    exit_code = 2


class SimulationError(BtGraspError):
    """The simulator reached a state it cannot continue from."""


def closest_names(name: str, candidates: list[str] | tuple[str, ...], n: int = 1) -> list[str]:
    """The known names closest to ``name``, best first: a case-insensitive match, else difflib's (cutoff 0.6)."""
    lowered = {c.lower(): c for c in candidates}
    if name.lower() in lowered:
        return [lowered[name.lower()]]
    return difflib.get_close_matches(name, list(candidates), n=n, cutoff=0.6)


def did_you_mean(name: str, candidates: list[str] | tuple[str, ...]) -> str:
    """``"; did you mean 'x'?"`` for the closest known name, or ``""`` (the one place this hint is made)."""
    close = closest_names(name, candidates)
    return f"; did you mean '{close[0]}'?" if close else ""
