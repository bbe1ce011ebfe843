"""The commands of README.md's "Command line" table (and docs/benchmarks.md's, where the developer benchmarks
moved), and the CLI invocations a test source makes.

Used by ``tests/test_readme_commands.py`` to check that every README command is run by some test. An
invocation is read from a test's syntax tree, not its text: the string literals handed to the CLI, in a list
(``[*BT, "eval", "run", ...]``, ``main(["tree", "run", ...])``) or as a helper's arguments
(``_bt("bench", "sim", "--json")``, ``run_cli(capsys, "tree", "show", ...)``), in a file that reaches the CLI
(it names ``bt_grasp.cli.main`` or the ``bt-grasp`` script). A command in a comment or a docstring is no test.
"""

from __future__ import annotations

import ast
import itertools
import re
from dataclasses import dataclass

#: a command word of the table, with its alternatives (``status\|stop``)
_WORD = re.compile(r"[a-z][a-z-]*(?:\\\|[a-z][a-z-]*)*")
#: strings that only say "this is the CLI" ahead of the command (``sys.executable, "-m", "bt_grasp.cli.main"``)
_LAUNCH = frozenset({"-m", "bt_grasp.cli.main"})
_MARKERS = frozenset({"bt_grasp.cli.main", "bt-grasp"})


@dataclass(frozen=True)
class Command:
    """One README command: its words (``bench perception``) and the bare switches that make it a row of its
    own (``--noise-sweep``)."""

    words: tuple[str, ...]
    flags: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        return " ".join((*self.words, *self.flags))


@dataclass(frozen=True)
class Invocation:
    """The string literals of one CLI call: ``head``, the consecutive ones it starts with; ``strings``, all."""

    head: tuple[str, ...]
    strings: frozenset[str]


def readme_commands(readme: str, section: str = "Command line") -> list[Command]:
    """Every command the "## Command line" table of README.md lists (or the table of another page's section:
    docs/benchmarks.md's "## Commands"), alternatives expanded, in order."""
    _, found, rest = readme.partition(f"\n## {section}\n")
    assert found, f"no '## {section}' section"
    commands: list[Command] = []
    for line in rest.split("\n## ", 1)[0].splitlines():
        row = re.match(r"\|\s*`bt-grasp ([^`]+)`", line)
        if row is None:
            continue
        tokens = row[1].split()
        if tokens[0].startswith("--"):  # `bt-grasp --version`
            commands.append(Command((tokens[0],)))
            continue
        i = 0
        choices: list[list[str]] = []
        while i < len(tokens) and _WORD.fullmatch(tokens[i]):
            choices.append(tokens[i].split("\\|"))
            i += 1
        flags: list[str] = []
        # a switch right after the words that takes no value and is not optional names a row of its own
        while i < len(tokens) and tokens[i].startswith("--") and (
            i + 1 == len(tokens) or tokens[i + 1].startswith(("[", "--"))
        ):
            flags.append(tokens[i])
            i += 1
        for words in itertools.product(*choices):
            command = Command(tuple(words), tuple(flags))
            if command not in commands:
                commands.append(command)
    return commands


def _reaches_cli(tree: ast.AST) -> bool:
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value in _MARKERS:
            return True
        if isinstance(node, ast.ImportFrom) and node.module == "bt_grasp.cli.main":
            return True
    return False


def _is_launch(node: ast.expr) -> bool:
    """What may stand before the command: the executable, ``-m bt_grasp.cli.main``, ``*BT``, ``capsys``."""
    if isinstance(node, ast.Constant):
        return node.value in _LAUNCH
    return isinstance(node, ast.Starred | ast.Name | ast.Attribute | ast.Call)


def cli_invocations(source: str) -> list[Invocation]:
    """The CLI calls a test module's source makes (nothing when the module never reaches the CLI)."""
    tree = ast.parse(source)
    if not _reaches_cli(tree):
        return []
    found: list[Invocation] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.List | ast.Tuple):
            elements = node.elts
        elif isinstance(node, ast.Call) and not (
            isinstance(node.func, ast.Attribute) and node.func.attr == "parametrize"
        ):
            elements = node.args
        else:
            continue
        i = 0
        while i < len(elements) and _is_launch(elements[i]):
            i += 1
        strings = [e.value for e in elements[i:] if isinstance(e, ast.Constant) and isinstance(e.value, str)]
        head: list[str] = []
        for e in elements[i:]:
            if not (isinstance(e, ast.Constant) and isinstance(e.value, str)):
                break
            head.append(e.value)
        if head:
            found.append(Invocation(tuple(head), frozenset(strings)))
    return found


def invokes(invocations: list[Invocation], command: Command) -> bool:
    """True when one of the invocations runs ``command`` (its words first, its switches anywhere after)."""
    n = len(command.words)
    return any(inv.head[:n] == command.words and set(command.flags) <= inv.strings for inv in invocations)
