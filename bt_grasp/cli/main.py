"""`bt-grasp`: the entry point. Sub-command groups live in their own modules and are added here.

Every error a user can act on (a ``BtGraspError`` with ``exit_code`` 2) is printed as one sentence on
stderr; nothing else of it (no traceback) reaches the user. Every command has the one error format
``bt-grasp: error: ...`` (``ERROR_PREFIX``), usage errors included.
"""

from __future__ import annotations

import os
import sys

from bt_grasp.process.numeric_threads import use_one_blas_thread

use_one_blas_thread()  # before anything imports numpy (this process and the ones it starts)

import typer  # noqa: E402

from bt_grasp.cli import ERROR_PREFIX  # noqa: E402
from bt_grasp.errors import BtGraspError  # noqa: E402
from bt_grasp.files.terminal_text import shown  # noqa: E402

INTERRUPTED = 130  # the exit code of a command Ctrl-C ended (128 + SIGINT)

#: every top-level command and the ``bt_grasp.cli`` modules that register it, in the order of ``--help``.
#: A command line that names one of them imports only its modules (issue 27: importing all ten cost
#: ~30-60 ms of every command); anything else (``--help``, ``--version``, no command, a mistyped one, shell
#: completion) imports them all. ``tests/test_cli_import_cost.py`` checks the table against the modules.
COMMAND_MODULES: dict[str, tuple[str, ...]] = {
    "init": ("init_cmd",),
    "scene": ("scene_cmd",),
    "demo": ("demo_cmd",),
    "run": ("run_cmd",),
    "tree": ("tree_cmd",),
    "calibrate": ("calibrate_cmd",),
    "replay": ("replay_cmd",),
    "bench": ("bench_extra_cmd", "bench_cmd", "bench_eval_cmd", "bench_cell_cmd"),
    "eval": ("eval_cmd",),
    "resident": ("resident_cmd",),
    "detector": ("detector_cmd",),
    "twin": ("twin_cmd",),
    "perceive": ("perceive_cmd",),
    "camera": ("camera_cmd",),
}


def _version_callback(value: bool) -> None:
    if value:
        from importlib.metadata import version

        typer.echo(f"bt-grasp {version('bt-grasp')}")
        raise typer.Exit()


def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """bt-grasp: run, inspect and debug behaviour trees that pick objects with a simulated UR5."""


def modules_for(args: list[str]) -> tuple[str, ...]:
    """The command modules a command line needs: its command's, or all of them (see COMMAND_MODULES)."""
    completing = any(name.startswith("_BT_GRASP") and name.endswith("_COMPLETE") for name in os.environ)
    if args and args[0] in COMMAND_MODULES and not completing:
        return COMMAND_MODULES[args[0]]
    return tuple(name for names in COMMAND_MODULES.values() for name in names)


def build_app(modules: tuple[str, ...]) -> typer.Typer:
    """The ``bt-grasp`` application with the commands of ``modules`` (``bt_grasp.cli`` module names)."""
    app = typer.Typer(
        name="bt-grasp",
        help="Behaviour-tree vision-guided grasping with a simulated UR5 and RealSense D435.",
        no_args_is_help=True,
        add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
        pretty_exceptions_enable=False,
    )
    app.callback()(_root)
    # Each command group registers itself on `app`; import order is the order in --help.
    for name in modules:
        try:
            module = __import__(f"bt_grasp.cli.{name}", fromlist=["register"])
        except ModuleNotFoundError as exc:
            if exc.name != f"bt_grasp.cli.{name}":
                raise
            continue
        module.register(app)
    return app


#: the longest error sentence printed: one that quotes a file's value of 5,000 characters is cut in its middle, the
#: file and the place it names (its start) and what is expected (its end) kept
MAX_SENTENCE_CHARS = 1000


def _bounded(sentence: str) -> str:
    if len(sentence) <= MAX_SENTENCE_CHARS:
        return sentence
    return sentence[: MAX_SENTENCE_CHARS - 300] + " [...] " + sentence[-290:]


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the process exit code."""
    args = sys.argv[1:] if argv is None else list(argv)
    app = build_app(modules_for(args))
    if args[:1] == ["run"]:
        from bt_grasp.cli.run_cmd import fill_optional_values

        args = fill_optional_values(args)
    if args[:1] and args[0] in ("perceive", "camera"):  # --device [SERIAL]
        from bt_grasp.cli.device_option import fill_device_value

        args = fill_device_value(args)
    try:
        rv = app(args=args, standalone_mode=False, prog_name="bt-grasp")  # also names the completion variable
    except BtGraspError as exc:  # its text may quote a file or a peer: control characters are shown, not obeyed
        typer.echo(f"{ERROR_PREFIX}{_bounded(shown(str(exc), newlines=False))}", err=True)
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
