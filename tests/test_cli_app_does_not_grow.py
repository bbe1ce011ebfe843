"""`main()` called many times in one process (the test suite, the resident, an embedding program) must cost the
same each time. Until issue 26's suite work it registered every command group again on one module-level app at
each call, so the app grew by a copy of every command per call and the 40th call cost ~25x the second: in the
whole suite, in-process CLI tests late in the run took 15-19 s each (`tests/tree/test_bad_trees.py` alone 707 s
of a 51-minute run). The check is structural (the number of commands click sees), not a timing."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import click
import typer

from bt_grasp.cli import main as cli

REPO = Path(__file__).resolve().parents[1]
BAD_TREE = REPO / "tests" / "data" / "bad_trees" / "bad_bool_port.xml"


def _commands_in(app: typer.Typer) -> int:
    def walk(command: click.Command) -> int:
        children = getattr(command, "commands", {})
        return 1 + sum(walk(child) for child in children.values())

    return walk(typer.main.get_command(app))


def test_repeated_main_calls_do_not_grow_the_command_table() -> None:
    every_module = cli.modules_for(["--help"])
    before = _commands_in(cli.build_app(every_module))
    assert before >= 30, before  # every group and command of bt-grasp (a sanity floor: 37 today)
    for _ in range(5):
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            assert cli.main(["tree", "validate", str(BAD_TREE)]) == 2
            assert cli.main(["bench", "--help"]) == 0
            assert cli.main(["eval", "--help"]) == 0
            assert cli.main(["--help"]) == 0
    assert _commands_in(cli.build_app(every_module)) == before


def test_each_build_is_a_new_app() -> None:
    modules = cli.modules_for(["tree", "validate", "x.xml"])
    first, second = cli.build_app(modules), cli.build_app(modules)
    assert first is not second
    assert _commands_in(first) == _commands_in(second)
