"""How the live server's own log lines reach the terminal (`run --live`).

The Foxglove SDK logs through Python's ``logging`` (logger ``foxglove``): a viewer that breaks the protocol, a
dropped client. Its messages quote what the client sent (``unknown variant `...```), so anyone who reaches the
port could write terminal control sequences into the user's terminal (found by the pre-review attack: a
window title and colours set from a WebSocket message). Here each line is printed once, prefixed, cut to one
line of at most 300 characters, with control characters shown (``bt_grasp.files.terminal_text``)."""

from __future__ import annotations

import logging
import sys

from bt_grasp.files.terminal_text import shown

MAX_LINE = 300


class LiveServerLog(logging.Handler):
    """Warnings and errors of the Foxglove SDK, one safe line each on stderr."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = shown(record.getMessage(), newlines=False)
            sys.stderr.write(f"live server: {text[:MAX_LINE]}{'...' if len(text) > MAX_LINE else ''}\n")
        except Exception:  # a log line must never stop the run
            self.handleError(record)


def show_live_server_log() -> None:
    """Route the ``foxglove`` logger's warnings and errors through :class:`LiveServerLog` (once)."""
    logger = logging.getLogger("foxglove")
    if not any(isinstance(h, LiveServerLog) for h in logger.handlers):
        handler = LiveServerLog(logging.WARNING)
        logger.addHandler(handler)
    logger.setLevel(logging.WARNING)
    logger.propagate = False
