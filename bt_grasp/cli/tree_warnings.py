"""The tree package's warnings as the CLI shows them: one line each on stderr, ``bt-grasp: warning: ...``.

A tree that loads as BehaviorTree.CPP would load it may still hold something a user should hear of (a
TreeNodesModel that disagrees with the registered node, a literal whose tail is ignored, a SubTree remapping a
port its model does not list). The library logs these with ``logging``; the tree commands show each once,
as plain text on one line (no markup is interpreted; control characters are shown as escapes)."""

from __future__ import annotations

import logging
import sys

from bt_grasp.files.terminal_text import shown

WARNING_PREFIX = "bt-grasp: warning: "


class _OnceToStderr(logging.Handler):
    def __init__(self) -> None:
        super().__init__(level=logging.WARNING)
        self._said: set[str] = set()

    def emit(self, record: logging.LogRecord) -> None:
        try:
            # one line whatever the file's text held, its control characters shown, never obeyed
            text = shown(" ".join(record.getMessage().split()), newlines=False)
        except Exception:  # a malformed record must not end the command
            return
        if text in self._said:
            return
        self._said.add(text)
        sys.stderr.write(f"{WARNING_PREFIX}{text}\n")


def show_tree_warnings() -> None:
    """Route ``bt_grasp.tree``'s warnings (not its info or debug lines) to stderr, once each."""
    logger = logging.getLogger("bt_grasp.tree")
    logger.setLevel(logging.WARNING)
    for handler in [h for h in logger.handlers if isinstance(h, _OnceToStderr)]:
        logger.removeHandler(handler)  # a new command (an in-process caller may run several) says each again
    logger.addHandler(_OnceToStderr())
    logger.propagate = False
