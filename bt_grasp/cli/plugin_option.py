"""The options every command that loads trees shares for users' own nodes (docs/own-leaves.md): ``--leaves``, and
on the ``tree`` commands ``--no-plugins`` and ``--plugin NAME`` to choose the installed plugins."""

from __future__ import annotations

from typing import Any

import typer

from bt_grasp.errors import InputError

LEAVES_HELP = (
    "A Python file (my_leaves.py) or module (my_pkg.nodes) whose register(registry) adds your own nodes "
    "and failure reasons (repeatable); installed bt_grasp.leaves entry points are loaded too."
)
NO_PLUGINS_HELP = "Leave every installed plugin (bt_grasp.leaves entry point) out; --leaves still loads."
PLUGIN_HELP = ("Load only this installed plugin (its entry point or distribution name; repeatable), leaving the "
               "other installed ones out.")


def leaves_option() -> Any:
    """A fresh ``--leaves`` option (typer wants one object per command)."""
    return typer.Option([], "--leaves", help=LEAVES_HELP, metavar="FILE.py|MODULE")


def no_plugins_option() -> Any:
    """A fresh ``--no-plugins`` flag."""
    return typer.Option(False, "--no-plugins", help=NO_PLUGINS_HELP)


def plugin_option() -> Any:
    """A fresh ``--plugin NAME`` option (repeatable)."""
    return typer.Option([], "--plugin", help=PLUGIN_HELP, metavar="NAME")


def installed_choice(no_plugins: bool, plugins: list[str]) -> bool | tuple[str, ...]:
    """Which installed plugins to load: all (True), none (False), or those named. Both options at once is an
    error (an InputError, exit 2)."""
    if no_plugins and plugins:
        raise InputError("--no-plugins", "leaves every installed plugin out; --plugin NAME keeps one: give one of them")
    if no_plugins:
        return False
    return tuple(plugins) if plugins else True
