"""The ``--leaves`` option every command that loads trees shares (users' own nodes, docs/own-leaves.md)."""

from __future__ import annotations

from typing import Any

import typer

LEAVES_HELP = (
    "A Python file (my_leaves.py) or module (my_pkg.nodes) whose register(registry) adds your own nodes "
    "and failure reasons (repeatable); installed bt_grasp.leaves entry points are always loaded."
)


def leaves_option() -> Any:
    """A fresh ``--leaves`` option (typer wants one object per command)."""
    return typer.Option([], "--leaves", help=LEAVES_HELP, metavar="FILE.py|MODULE")
