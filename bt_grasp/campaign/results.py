"""The durable record of a campaign: one JSON-lines file, one row per finished episode.

Only the coordinating process writes it; each row is written with one ``write`` and flushed to disk
(``fsync``) before the next episode is counted as done, so a crash loses at most the row being written. A
torn last line (the process died mid-write) is cut off when the file is opened again; that episode runs
again on resume. Parquet is an export of this file, never the record.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from bt_grasp.bounded_io import MAX_RESULTS_BYTES, read_user_file
from bt_grasp.errors import InputError

SUFFIX = ".jsonl"


def results_path(out_dir: Path, campaign_name: str) -> Path:
    return Path(out_dir) / f"{campaign_name}{SUFFIX}"


def read_rows(path: Path, *, repair: bool = False) -> list[dict[str, Any]]:
    """Every complete row of a results file; a torn last line is dropped (and cut from the file if ``repair``)."""
    path = Path(path)
    if not path.exists():
        raise InputError(path, "no such results file")
    data = read_user_file(path, MAX_RESULTS_BYTES)
    end = data.rfind(b"\n") + 1
    if end < len(data) and repair:
        with open(path, "r+b") as f:
            f.truncate(end)
            f.flush()
            os.fsync(f.fileno())
    rows = []
    for number, line in enumerate(data[:end].splitlines(), start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except json.JSONDecodeError as exc:
            raise InputError(path, f"not a JSON object ({exc.msg})", number) from None
        if not isinstance(row, dict) or "episode" not in row:
            raise InputError(path, "not a campaign results row (no 'episode' column)", number)
        rows.append(row)
    return rows


class ResultsWriter:
    """Appends rows; each one on disk before :meth:`append` returns."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def append(self, row: dict[str, Any]) -> None:
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


def export_parquet(rows: Iterable[dict[str, Any]], out: Path) -> Path:
    """Write rows as a Parquet table; nested columns (params, retries, judge, environment) as JSON text."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    flat = [
        {k: (json.dumps(v, sort_keys=True) if isinstance(v, dict | list) else v) for k, v in row.items()}
        for row in rows
    ]
    columns: dict[str, list[Any]] = {}
    for row in flat:
        for key in row:
            columns.setdefault(key, [])
    for row in flat:
        for key, values in columns.items():
            values.append(row.get(key))
    out.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.table(columns), out)
    return out
