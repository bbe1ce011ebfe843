"""Text that reads at the terminal's width, and at 80 columns in a pipe: prose wraps between words, values are never
cut, and a command a user may copy is kept on one line (``COLUMNS`` is honoured, as Rich and the shell do)."""

from __future__ import annotations

import shutil
import textwrap

#: the width of a pipe, a file or a terminal that does not say
PIPE_COLUMNS = 80


def columns() -> int:
    """The terminal's width (``COLUMNS`` first), else 80."""
    return max(20, shutil.get_terminal_size((PIPE_COLUMNS, 24)).columns)


def wrap(text: str, *, indent: str = "", hang: str = "  ", width: int | None = None) -> str:
    """``text`` wrapped between words to ``width`` (the terminal's), its first line after ``indent``, the next
    after ``indent + hang``; a word longer than a line (a path) stands alone on its line, whole."""
    return textwrap.fill(text, width or columns(), initial_indent=indent,
                         subsequent_indent=indent + hang, break_long_words=False, break_on_hyphens=False)
