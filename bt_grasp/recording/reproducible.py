"""Logs with no wall-clock reading in them, for byte-for-byte comparison (``SOURCE_DATE_EPOCH``).

A log places simulated time 0 at the run's real start date, and its result records how long the tick loop took
in wall time: two runs of the same command with the same seed therefore write the same ticks but not the same
bytes. With ``SOURCE_DATE_EPOCH`` set (the reproducible-builds convention: whole seconds since 1970-01-01 UTC),
the log's time origin and its attachments' times are that date, and the result's wall-clock figures are written
as null, so the same command with the same seed writes the same file on any machine at any speed (what issue 27
asks of a log). Everything else a reader relies on is unchanged; the terminal summary still prints the wall time.
"""

from __future__ import annotations

from collections.abc import Mapping

from bt_grasp.errors import InputError

ENV = "SOURCE_DATE_EPOCH"
#: the largest date accepted (9999-12-31): later ones overflow the log's nanosecond times
_MAX_S = 253_402_300_799


def log_epoch_ns(environ: Mapping[str, str]) -> int | None:
    """The log's fixed time origin in ns from ``SOURCE_DATE_EPOCH``; None when the variable is unset or empty."""
    text = environ.get(ENV, "").strip()
    if not text:
        return None
    if not text.isdigit() or int(text) > _MAX_S:
        shown = text if len(text) <= 40 else text[:40] + "..."
        raise InputError(ENV, f"expected whole seconds since 1970-01-01 UTC (0 to {_MAX_S}), got {shown!r}")
    return int(text) * 1_000_000_000


def without_wall_clock(result: Mapping[str, object]) -> dict[str, object]:
    """``result`` (a /run/result message) with its wall-clock figures null: ``wall_time_s`` and the planner's
    ``planning.wall_s``."""
    out = dict(result)
    if "wall_time_s" in out:
        out["wall_time_s"] = None
    planning = out.get("planning")
    if isinstance(planning, Mapping) and "wall_s" in planning:
        out["planning"] = {**planning, "wall_s": None}
    return out
