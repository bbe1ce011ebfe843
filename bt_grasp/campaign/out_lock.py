"""One campaign coordinator per ``--out`` folder, by a lock the kernel holds for it.

Two coordinators appending to one results file would write every episode twice. ``fcntl.flock`` on
``<out>/.campaign.lock`` is held for the coordinator's whole run and released by the kernel when the process
ends in any way (a ``kill -9`` included), so a killed campaign can be resumed at once and no stale lock is
ever left to clean up by hand. The lock file holds the holder's pid, for the refusal sentence only.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from bt_grasp.errors import InputError

LOCK_NAME = ".campaign.lock"


@contextmanager
def campaign_lock(out_dir: Path) -> Iterator[None]:
    """Hold ``out_dir``'s campaign lock, or raise :class:`InputError` (exit 2) when another coordinator does."""
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "unknown"
            raise InputError(
                out_dir, f"another campaign (pid {holder}) is running with this --out folder; wait for it or "
                "choose another folder"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        os.close(fd)  # closing the descriptor releases the lock
