"""The durable record of a campaign: one JSON-lines file, one row per finished episode.

Only the coordinating process writes it; each row is written with one ``write`` and flushed to disk
(``fsync``) before the next episode is counted as done, so a crash loses at most the row being written. A
torn last line (the process died mid-write) is cut off when the file is opened again; that episode runs
again on resume. Parquet is an export of this file, never the record.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import cast

from bt_grasp.campaign.rows import ReportRow
from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import MAX_RESULTS_BYTES, read_user_file
from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.files.output_files import open_output_stream, write_output_file

SUFFIX = ".jsonl"


def results_path(out_dir: Path, campaign_name: str) -> Path:
    return Path(out_dir) / f"{campaign_name}{SUFFIX}"


def read_rows(path: Path, *, repair: bool = False) -> list[JsonObject]:
    """Every complete row of a results file; a torn last line is dropped (and cut from the file if ``repair``)."""
    path = Path(path)
    if not path.exists():
        raise InputError(path, "no such results file")
    data = read_user_file(path, MAX_RESULTS_BYTES)
    end = data.rfind(b"\n") + 1
    if end < len(data) and repair:
        fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | os.O_CLOEXEC)  # the file itself, never a link's target
        try:
            os.ftruncate(fd, end)
            os.fsync(fd)
        finally:
            os.close(fd)
    return [row for _, row in _numbered_rows(path, data[:end])]


#: the longest row a results file may hold (bt_grasp writes about 1-2 KB a row)
MAX_ROW_BYTES = 1 << 20


def _numbered_rows(path: Path, data: bytes) -> list[tuple[int, JsonObject]]:
    rows: list[tuple[int, JsonObject]] = []
    for number, line in enumerate(data.splitlines(), start=1):
        if not line.strip():
            continue
        if len(line) > MAX_ROW_BYTES:
            raise InputError(path, f"a row of {len(line):,} bytes, more than the {MAX_ROW_BYTES:,} a row may be",
                             number)
        try:
            row = json.loads(line.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise InputError(path, f"not UTF-8 text (byte {exc.start + 1} of the line)", number) from None
        except json.JSONDecodeError as exc:
            raise InputError(path, f"not a JSON object ({exc.msg})", number) from None
        except RecursionError:
            raise InputError(path, "not a campaign results row (JSON nested too deeply to read)", number) from None
        except ValueError as exc:  # an integer of more digits than Python converts
            raise InputError(path, f"not a JSON object ({str(exc).split(':')[0]})", number) from None
        if not isinstance(row, dict) or "episode" not in row:
            raise InputError(path, "not a campaign results row (no 'episode' column)", number)
        rows.append((number, row))
    return rows


#: more retries than any episode makes (the report draws one bar per count)
MAX_RETRIES = 10_000
#: the longest text a report reads from a row (a tree's path, a leaf's path, a reason), and the most leaves a row's
#: retries may name: a 100 MB leaf name took `eval report` past 13 GB and two minutes
MAX_FIELD_CHARS = 4096
MAX_RETRIED_LEAVES = 1000
#: the longest time a report draws (a week, in seconds): +-1.7e308 s ended in `ValueError: arange`
MAX_TIME_S = 7 * 24 * 3600.0
#: the most ticks an episode runs (a re-simulation's limit)
MAX_TICKS = 10_000_000
_TEXT = (str,)


def _is_int(value: object, low: int = -(2**63), high: int = 2**63 - 1) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and low <= value <= high


def _is_finite(value: object) -> bool:
    return (isinstance(value, float) and math.isfinite(value)) or _is_int(value)


def _is_time(value: JsonValue) -> bool:
    return _is_finite(value) and isinstance(value, int | float) and 0 <= value <= MAX_TIME_S


def _is_label(value: JsonValue, optional: bool = False) -> bool:
    return (optional and value is None) or (isinstance(value, str) and len(value) <= MAX_FIELD_CHARS)


def _is_retries(value: JsonValue) -> bool:
    return (isinstance(value, dict) and len(value) <= MAX_RETRIED_LEAVES
            and all(len(k) <= MAX_FIELD_CHARS and _is_int(n, 0, MAX_RETRIES) for k, n in value.items()))


def _check_text(value: str) -> bool:
    """A string that can be written out again (no lone surrogate from a ``\\udcff`` escape)."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


_TEXT_UP_TO = f"a string of at most {MAX_FIELD_CHARS} characters"
_COLUMNS: dict[str, tuple[str, Callable[[JsonValue], bool]]] = {
    # column -> (what it must be, check)
    "episode": (_TEXT_UP_TO, _is_label),
    "tree": (_TEXT_UP_TO, _is_label),
    "scene": (_TEXT_UP_TO, _is_label),
    "fault_plan": (_TEXT_UP_TO, _is_label),
    "seed": ("an integer", _is_int),
    "success": ("true or false", lambda v: isinstance(v, bool)),
    "failure_reason": (f"{_TEXT_UP_TO} or null", lambda v: _is_label(v, optional=True)),
    "failed_leaf": (f"{_TEXT_UP_TO} or null", lambda v: _is_label(v, optional=True)),
    "ticks": (f"an integer or null (0 to {MAX_TICKS:,})", lambda v: v is None or _is_int(v, 0, MAX_TICKS)),
    "sim_time_s": (f"a finite number of seconds from 0 to {MAX_TIME_S:g}", _is_time),
    "episode_wall_s": (f"a finite number of seconds from 0 to {MAX_TIME_S:g}", _is_time),
    "retries_total": (f"an integer from 0 to {MAX_RETRIES}", lambda v: _is_int(v, 0, MAX_RETRIES)),
    "retries": (f"an object of at most {MAX_RETRIED_LEAVES} leaf paths (each {_TEXT_UP_TO}) to retry counts "
                f"(0 to {MAX_RETRIES})", _is_retries),
}
_OPTIONAL_COLUMNS: dict[str, tuple[str, Callable[[JsonValue], bool]]] = {
    "campaign": (_TEXT_UP_TO, _is_label),
    "mcap": (f"{_TEXT_UP_TO} or null", lambda v: _is_label(v, optional=True)),
    # the failed leaf's path, its name in every output (rows written before it have only failed_leaf)
    "failed_path": (f"{_TEXT_UP_TO} or null", lambda v: _is_label(v, optional=True)),
    "params": ("an object", lambda v: isinstance(v, dict)),
    "environment": ("an object or null", lambda v: v is None or (
        isinstance(v, dict) and isinstance(v.get("libraries") or {}, dict))),
}


def _check_row(path: Path, number: int, row: JsonObject) -> None:
    for column, (expected, ok) in _COLUMNS.items():
        if column not in row:
            raise InputError(path, f"the row has no '{column}' column (a report needs it)", number)
        if not ok(row[column]):
            raise InputError(path, f"'{column}' is {_shown(row[column])}, not {expected}", number)
    for column, (expected, ok) in _OPTIONAL_COLUMNS.items():
        if column in row and not ok(row[column]):
            raise InputError(path, f"'{column}' is {_shown(row[column])}, not {expected}", number)
    try:
        text = json.dumps(row, ensure_ascii=False)
    except RecursionError:
        raise InputError(path, "the row is nested too deeply to report on", number) from None
    if not _check_text(text):
        raise InputError(path, "the row holds text that is not valid Unicode (a lone surrogate)", number)


def _shown(value: object) -> str:
    text = json.dumps(value, ensure_ascii=True)
    return text if len(text) <= 40 else text[:37] + "..."


def read_report_rows(path: Path) -> list[ReportRow]:
    """The complete rows of a results file, each checked for the columns a report reads, with their types;
    a row that lacks one or holds the wrong type is an ``InputError`` naming the line and the column."""
    path = Path(path)
    if not path.exists():
        raise InputError(path, "no such results file")
    data = read_user_file(path, MAX_RESULTS_BYTES)
    numbered = _numbered_rows(path, data[: data.rfind(b"\n") + 1])
    for number, row in numbered:
        _check_row(path, number, row)
    return [cast("ReportRow", row) for _, row in numbered]  # what _check_row made sure of


class ResultsWriter:
    """Appends rows; each one on disk before :meth:`append` returns."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._fd = open_output_stream(self.path, "--out", append=True)  # never through a link, never a FIFO

    def append(self, row: Mapping[str, object]) -> None:
        line = (json.dumps(row, sort_keys=False, default=str) + "\n").encode()
        os.write(self._fd, line)
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def export_parquet(rows: Iterable[Mapping[str, object]], out: Path) -> Path:
    """Write rows as a Parquet table; nested columns (params, retries, judge, environment) as JSON text."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    flat = [
        {k: (json.dumps(v, sort_keys=True) if isinstance(v, dict | list) else v) for k, v in row.items()}
        for row in rows
    ]
    columns: dict[str, list[object]] = {}
    for row in flat:
        for key in row:
            columns.setdefault(key, [])
    for row in flat:
        for key, values in columns.items():
            values.append(row.get(key))
    buffer = pa.BufferOutputStream()
    pq.write_table(pa.table(columns), buffer)
    return write_output_file(out, buffer.getvalue().to_pybytes(), "--out", example="results.parquet")
