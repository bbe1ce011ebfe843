"""`bt-grasp`: the entry point. Sub-command groups live in their own modules and are added here.

Every error a user can act on (a ``BtGraspError`` with ``exit_code`` 2) is printed as one sentence on
stderr; nothing else of it (no traceback) reaches the user. Every command has the one error format
``bt-grasp: error: ...`` (``ERROR_PREFIX``), usage errors included.
"""

from __future__ import annotations

import os
import sys
from importlib.metadata import version as _dist_version

import typer

from bt_grasp.cli import ERROR_PREFIX
from bt_grasp.errors import BtGraspError

app = typer.Typer(
    name="bt-grasp",
    help="Behaviour-tree vision-guided grasping with a simulated UR5 and RealSense D435.",
    no_args_is_help=True,
    add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
    pretty_exceptions_enable=False,
)


INTERRUPTED = 130  # the exit code of a command Ctrl-C ended (128 + SIGINT)


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"bt-grasp {_dist_version('bt-grasp')}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """bt-grasp: run, inspect and debug behaviour trees that pick objects with a simulated UR5."""


def _register() -> None:
    # Each command group registers itself on `app`; import order is the order in --help.
    from bt_grasp.cli import scene_cmd

    scene_cmd.register(app)
    commands = ("demo_cmd", "run_cmd", "tree_cmd", "calibrate_cmd", "replay_cmd", "bench_extra_cmd", "bench_cmd")
    for name in (*commands, "eval_cmd", "bench_eval_cmd", "resident_cmd", "detector_cmd"):
        try:
            module = __import__(f"bt_grasp.cli.{name}", fromlist=["register"])
        except ModuleNotFoundError as exc:
            if exc.name != f"bt_grasp.cli.{name}":
                raise
            continue
        module.register(app)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit code."""
    _register()
    from bt_grasp.cli.run_cmd import fill_optional_values

    args = sys.argv[1:] if argv is None else list(argv)
    if args[:1] == ["run"]:
        args = fill_optional_values(args)
    try:
        rv = app(args=args, standalone_mode=False, prog_name="bt-grasp")  # also names the completion variable
    except BtGraspError as exc:
        typer.echo(f"{ERROR_PREFIX}{exc}", err=True)
        code = exc.exit_code
    except typer.Exit as exc:
        code = exc.exit_code
    except typer.Abort:
        typer.echo(f"{ERROR_PREFIX}aborted", err=True)
        code = INTERRUPTED
    except KeyboardInterrupt:
        typer.echo(f"{ERROR_PREFIX}interrupted (Ctrl-C)", err=True)
        code = INTERRUPTED
    except Exception as exc:
        # click's usage errors (typer vendors click, so match by shape rather than by class)
        fmt, exit_code = getattr(exc, "format_message", None), getattr(exc, "exit_code", None)
        if callable(fmt) and isinstance(exit_code, int):
            ctx = getattr(exc, "ctx", None)
            where = f" (see `{ctx.command_path} --help`)" if ctx is not None else ""
            if fmt():  # empty: a group called with no command, whose help was printed instead
                typer.echo(f"{ERROR_PREFIX}{fmt()}{where}", err=True)
            code = exit_code
        else:
            raise
    else:
        code = rv if isinstance(rv, int) else 0
        if code == INTERRUPTED:  # typer turns Ctrl-C into a silent return of 130 (no command returns 130)
            typer.echo(f"{ERROR_PREFIX}interrupted (Ctrl-C)", err=True)
    sys.stdout.flush()
    sys.stderr.flush()
    if argv is None:
        # nanobind (OMPL) prints "leaked ..." lines at interpreter exit; users should not see them.
        os._exit(code)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
