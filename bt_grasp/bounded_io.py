"""One bounded reader for every file a user gives bt_grasp (trees, scenes, calibration, fault plans, campaign
files, results): a regular file no larger than its kind's limit, read with at most ``limit + 1`` bytes, so
``--faults /dev/zero``, a FIFO or a multi-gigabyte file is one sentence, not an exhausted machine."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError

#: text files a user writes by hand: trees, scenes, calibrations, fault plans, campaign files
MAX_TEXT_BYTES = 16 << 20
#: a campaign's results (JSON lines: about 1 KB an episode)
MAX_RESULTS_BYTES = 1 << 30


def read_user_file(path: str | Path, limit: int = MAX_TEXT_BYTES, *, error: type[InputError] = InputError) -> bytes:
    """The bytes of ``path``, or ``error(path, one sentence)``: missing, a folder, not a regular file (a device
    such as /dev/zero, a FIFO, a socket), unreadable, or larger than ``limit``."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise error(path, "no such file") from None
    except IsADirectoryError:
        raise error(path, "is a folder, not a file") from None
    except PermissionError:
        raise error(path, "cannot be read: permission denied") from None
    except OSError as exc:
        raise error(path, f"cannot be read: {exc.strerror or exc}") from None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(f.fileno())
        if stat.S_ISDIR(info.st_mode):
            raise error(path, "is a folder, not a file")
        if not stat.S_ISREG(info.st_mode):
            raise error(path, "is not a regular file (a device, pipe or socket); give a file")
        if info.st_size > limit:
            raise error(path, f"is {info.st_size} bytes, over the {limit}-byte limit for this kind of file")
        data = f.read(limit + 1)
    if len(data) > limit:
        raise error(path, f"is over the {limit}-byte limit for this kind of file")
    return data
