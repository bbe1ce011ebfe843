"""A RealSense recording a user gives: checked before pyrealsense2 is handed it.

pyrealsense2 2.59 reads the ROS 2 ``.db3`` format its recorder writes (and the RealSense Viewer's), and ROS 1
``.bag`` files. Every file a user gives is hostile: this module reads at most the first 100 bytes of it and asks
SQLite (read-only) for the two tables a recording has, so a truncated file, another program's file renamed
``.db3``, a folder or a device is one sentence naming the file and the problem. What the library itself then
refuses is turned into one sentence too (:func:`library_problem`).
"""

from __future__ import annotations

import enum
import os
import sqlite3
import stat
from pathlib import Path

from bt_grasp.errors import InputError

#: the first bytes of an SQLite database (a ROS 2 bag's .db3) and of a ROS 1 bag
SQLITE_MAGIC = b"SQLite format 3\x00"
ROSBAG_MAGIC = b"#ROSBAG V2.0\n"
#: SQLite header fields (https://www.sqlite.org/fileformat.html, "The Database Header")
_PAGE_SIZE_AT, _CHANGE_COUNTER_AT, _PAGE_COUNT_AT, _VALID_FOR_AT = 16, 24, 28, 92


class RecordingFormat(enum.Enum):
    DB3 = "db3"  # ROS 2 (SQLite): what pyrealsense2 2.59's recorder and the RealSense Viewer write
    BAG = "bag"  # ROS 1: older Viewer recordings


class RecordingError(InputError):
    """A recording file that cannot be read (exit code 2, one sentence naming the file)."""


def check_recording(path: str | Path) -> RecordingFormat:
    """The recording's format, or :class:`RecordingError`: missing, not a regular file, empty, neither an SQLite
    database nor a ROS 1 bag, a database shorter than its own header says (truncated), or a database without a
    recording's tables (another program's)."""
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise RecordingError(path, "no such file") from None
    except OSError as exc:
        raise RecordingError(path, f"cannot be read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise RecordingError(path, "is a folder, not a recording")
    if not stat.S_ISREG(info.st_mode):
        raise RecordingError(path, "is not a regular file (a device, pipe or socket); give a recording")
    try:
        with open(path, "rb") as f:
            head = f.read(100)
    except OSError as exc:
        raise RecordingError(path, f"cannot be read: {exc.strerror or exc}") from None
    if head.startswith(ROSBAG_MAGIC):
        return RecordingFormat.BAG
    if not head.startswith(SQLITE_MAGIC):
        what = "empty" if not head else "neither a RealSense recording (.db3, SQLite) nor a ROS 1 bag"
        raise RecordingError(path, f"is {what}")
    if len(head) < 100:
        raise RecordingError(path, f"is truncated: {len(head)} bytes, shorter than an SQLite header")
    _check_sqlite_size(path, head, info.st_size)
    _check_tables(path)
    return RecordingFormat.DB3


def _check_sqlite_size(path: Path, head: bytes, size: int) -> None:
    page_size = int.from_bytes(head[_PAGE_SIZE_AT:_PAGE_SIZE_AT + 2], "big")
    page_size = 65536 if page_size == 1 else page_size
    pages = int.from_bytes(head[_PAGE_COUNT_AT:_PAGE_COUNT_AT + 4], "big")
    counter = head[_CHANGE_COUNTER_AT:_CHANGE_COUNTER_AT + 4]
    # the page count is valid only when written by a version that keeps it (its "valid for" = the change counter)
    if pages and head[_VALID_FOR_AT:_VALID_FOR_AT + 4] == counter and size < pages * page_size:
        raise RecordingError(path, f"is truncated: {size} bytes, its header says {pages * page_size}")


def _read_only(path: str | Path) -> sqlite3.Connection:
    """The recording's database, opened read-only and immutable (nothing of it is written or locked)."""
    return sqlite3.connect(f"{Path(path).resolve().as_uri()}?mode=ro&immutable=1", uri=True)


def _check_tables(path: Path) -> None:
    try:
        db = _read_only(path)
    except sqlite3.Error as exc:
        raise RecordingError(path, f"cannot be opened as a database ({exc})") from None
    try:
        tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
        topics = [row[0] for row in db.execute("SELECT name FROM topics")] if "topics" in tables else []
    except sqlite3.Error as exc:
        raise RecordingError(path, f"is a damaged database ({exc})") from None
    finally:
        db.close()
    if not {"topics", "messages"} <= tables:
        raise RecordingError(path, "is an SQLite database but not a RealSense recording (no topics and messages)")
    if not any("/image/data" in name for name in topics):
        raise RecordingError(path, "holds no image stream (a RealSense recording of depth and colour is needed)")


def frames_held(path: str | Path) -> dict[str, int]:
    """How many pictures a ``.db3`` recording holds per image stream (its image-data topics), read from the file
    itself: what a playback that returned fewer frames should have returned."""
    db = _read_only(path)
    try:
        rows = db.execute("SELECT t.name, COUNT(*) FROM messages m JOIN topics t ON m.topic_id = t.id "
                          "WHERE t.name LIKE '%/image/data%' GROUP BY t.name").fetchall()
    finally:
        db.close()
    return {str(name): int(count) for name, count in rows}


def library_problem(path: str | Path, exc: Exception) -> RecordingError:
    """pyrealsense2's refusal of a recording as one sentence (its own reason, shortened to its last clause)."""
    text = " ".join(str(exc).split())
    reason = text.split("Reason:", 1)[-1].strip() or type(exc).__name__
    return RecordingError(path, f"pyrealsense2 cannot play it: {reason}")
