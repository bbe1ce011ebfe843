"""Errors raised while a tree runs (load errors are :class:`bt_grasp.errors.TreeFileError`)."""

from __future__ import annotations

from bt_grasp.errors import BtGraspError, TreeFileError


class TreeRuntimeError(BtGraspError):
    """A tree broke an invariant while ticking: a script read a missing variable, a port had no value.

    The tree file is what needs fixing, so the command line exits with code 2.
    """

    exit_code = 2

    def __init__(self, message: str, *, located: bool = False) -> None:
        super().__init__(message)
        #: the message already names the node (file:line, type and path) where the error happened
        self.located = located


class ScriptSyntaxError(ValueError):
    """A BT.CPP script does not parse. ``column`` is 1-based within the script text."""

    def __init__(self, script: str, problem: str, column: int | None = None) -> None:
        self.script = script
        self.problem = problem
        self.column = column
        where = f" at column {column}" if column else ""
        super().__init__(f"script {script!r}: {problem}{where}")


class PortValueError(ValueError):
    """A literal port value cannot be converted to the port's type (a load error once located)."""


class DeclarationError(ValueError):
    """A node, port or failure reason declared wrongly, or a name registered twice (one sentence).

    A ``ValueError``, so callers that caught those keep working; the plugin loader names the plugin with it."""


class UnknownNodes(TreeFileError):
    """A tree names several node types nothing registered: every one of them, each at its file and line
    (``problems``, one sentence each). Its own message is the first, then how many more (``tree validate`` and
    ``tree run`` print every one on its own line)."""

    def __init__(self, problems: list[TreeFileError]) -> None:
        first = problems[0]
        self.problems = tuple(problems)
        more = len(problems) - 1
        super().__init__(first.source, f"{first.problem} (and {more} more unknown node{'s' * (more > 1)}; "
                         "`bt-grasp tree validate` lists every one)", where=first.where)

    @property
    def lines(self) -> tuple[str, ...]:
        return tuple(p.message for p in self.problems)
