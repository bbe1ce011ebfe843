"""Run a command with its standard error on a pseudo-terminal, as a user's terminal: `bt-grasp run` draws its live
progress there (one line redrawn in place, ending with a carriage return) and only there, never into a pipe
(issue 43, finding 8). Tests that wait for the progress (a tick reached) read it this way."""

from __future__ import annotations

import os
import pty
import re
import subprocess
from collections.abc import Iterator, Sequence
from typing import Any


class TerminalStderr:
    """``subprocess.Popen(args, stderr=<a pseudo-terminal>, **kwargs)``; :meth:`lines` yields what it writes there,
    split at carriage returns and newlines (empty pieces left out)."""

    def __init__(self, args: Sequence[str], **kwargs: Any) -> None:
        self._master, slave = pty.openpty()
        try:
            self.proc = subprocess.Popen(list(args), stderr=slave, **kwargs)
        finally:
            os.close(slave)
        self._buffer = ""

    def lines(self) -> Iterator[str]:
        while True:
            try:
                chunk = os.read(self._master, 4096)
            except OSError:  # EIO: every writer closed the terminal (the command ended)
                chunk = b""
            if not chunk:
                if self._buffer.strip():
                    yield self._buffer
                self._buffer = ""
                return
            self._buffer += chunk.decode("utf-8", "replace")
            *done, self._buffer = re.split(r"[\r\n]", self._buffer)
            yield from (line for line in done if line.strip())

    def close(self) -> None:
        os.close(self._master)
