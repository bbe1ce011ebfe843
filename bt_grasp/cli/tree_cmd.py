"""`bt-grasp tree ...`: validate, show, convert and dry-run behaviour-tree files; write Groot2's node models.

Every problem with a file or argument prints one line on stderr (``bt-grasp: error: file:line: problem``) and exits 2.
"""

from __future__ import annotations

import io
import json
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from bt_grasp.cli import ERROR_PREFIX
from bt_grasp.cli.plugin_option import installed_choice, leaves_option, no_plugins_option, plugin_option
from bt_grasp.errors import InputError
from bt_grasp.files.output_files import check_output_file, write_output_file
from bt_grasp.files.terminal_text import shown

if TYPE_CHECKING:  # the tree package (py_trees) is imported when a command reads a tree, not for --help
    from bt_grasp.tree.registry import NodeRegistry

tree_app = typer.Typer(
    name="tree",
    help="Validate, show, convert and dry-run BehaviorTree.CPP v4 XML / YAML tree files.",
    no_args_is_help=True,
    add_completion=False,
)


def tree_registry(leaves: list[str] | None = None, no_plugins: bool = False,
                  plugins: list[str] | None = None) -> NodeRegistry:
    """The built-in nodes plus the robot leaves, plus the installed plugins' (all, none with ``--no-plugins``,
    or those ``--plugin`` names) and the ``--leaves`` nodes (a bad plugin raises PluginError, an InputError)."""
    from bt_grasp.behaviours import robot_registry

    return robot_registry(leaves or (), installed_choice(no_plugins, plugins or []))


def _fail(exc: InputError) -> typer.Exit:
    typer.echo(f"{ERROR_PREFIX}{shown(exc.message)}", err=True)  # control characters shown, never obeyed
    return typer.Exit(exc.exit_code)


def _show_tree_warnings() -> None:
    """The tree package's warnings as one line each (``bt-grasp: warning: ...``), nothing below them."""
    from bt_grasp.cli.tree_warnings import show_tree_warnings

    show_tree_warnings()


@tree_app.command("validate")
def validate_cmd(
    file: Path = typer.Argument(..., help="XML or YAML tree file."),
    leaves: list[str] = leaves_option(),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Check a tree file completely (nodes, ports, scripts, includes, subtrees) without running it."""
    from bt_grasp.tree.loader import load_tree

    _show_tree_warnings()
    try:
        tree = load_tree(file, tree_registry(leaves, no_plugins, plugins))
        from bt_grasp.behaviours.objects import check_detector_classes

        check_detector_classes(tree.nodes())  # a SelectObject's class against the tree's learned models
    except InputError as exc:
        raise _fail(exc) from None
    count = sum(1 for _ in tree.nodes())
    typer.echo(f"{file}: OK ({count} nodes, main tree {tree.main_tree})")


class ShowFormat(StrEnum):
    """`tree show --format`: a typed choice (completed by the shell, refused by the parser when unknown)."""

    text = "text"
    dot = "dot"
    png = "png"
    svg = "svg"


@tree_app.command("show")
def show_cmd(
    file: Path = typer.Argument(..., help="XML or YAML tree file."),
    fmt: ShowFormat = typer.Option(ShowFormat.text, "--format", "-f", help="How to draw it."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Write here instead of the terminal."),
    leaves: list[str] = leaves_option(),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Draw the expanded tree (subtrees inlined) as text, Graphviz dot, png or svg."""
    from rich.console import Console

    from bt_grasp.tree import render
    from bt_grasp.tree.loader import load_tree

    _show_tree_warnings()
    try:
        if fmt in ("png", "svg") and out is None:
            raise InputError("--out", f"--format {fmt} needs --out FILE")
        if out is not None:
            check_output_file(out, "--out", example=f"tree.{fmt}", inputs=(file,))
        tree = load_tree(file, tree_registry(leaves, no_plugins, plugins))
        if fmt == "text":
            if out is None:
                Console().print(render.rich_tree(tree.root))
            else:
                text = io.StringIO()
                Console(file=text, width=120, color_system=None).print(render.rich_tree(tree.root))
                write_output_file(out, text.getvalue(), "--out")
            return
        dot_text = render.to_dot(tree.root, tree.main_tree)
        if fmt == "dot":
            if out is None:
                typer.echo(dot_text, nl=False)
            else:
                write_output_file(out, dot_text, "--out")
            return
        assert out is not None
        write_output_file(out, render.render_image(dot_text, fmt), "--out")
        typer.echo(f"wrote {out}")
    except InputError as exc:
        raise _fail(exc) from None


@tree_app.command("convert")
def convert_cmd(
    source: Path = typer.Argument(..., help="Input tree file (.xml, .yaml, .yml)."),
    target: Path = typer.Argument(..., help="Output file; its extension chooses the format."),
    force: bool = typer.Option(False, "--force", help="Overwrite OUT if it exists."),
    leaves: list[str] = leaves_option(),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Convert between BT.CPP v4 XML and the YAML twin format (node types are not resolved: --leaves plugins
    are only loaded and checked). An existing OUT is kept unless --force."""
    from bt_grasp.tree.formats.convert import convert_file, format_of

    _show_tree_warnings()
    try:
        format_of(target)
        if target.exists() and source.exists() and target.resolve() == source.resolve():
            raise InputError(target, "is the input file; write the converted tree to another file")
        check_output_file(target, "TARGET", example="tree.yaml")  # not a link, a folder or a device
        if target.exists() and not force:
            raise InputError(target, "exists; pass --force to overwrite it")
        if leaves or plugins:
            tree_registry(leaves, no_plugins, plugins)
        convert_file(source, target)
    except InputError as exc:
        raise _fail(exc) from None
    typer.echo(f"wrote {target}")


def _parse_substitutions(values: list[str]) -> dict[str, str]:
    rules: dict[str, str] = {}
    for value in values:
        node, sep, replacement = value.partition("=")
        if not sep or not node.strip() or not replacement.strip():
            raise InputError("--substitute", f"'{value}' is not NODE=REPLACEMENT (e.g. Perceive=AlwaysSuccess)")
        rules[node.strip()] = replacement.strip()
    return rules


@tree_app.command("run")
def run_cmd(
    file: Path = typer.Argument(..., help="XML or YAML tree file."),
    dry: bool = typer.Option(
        False, "--dry", help="Run without robot or simulator, robot leaves replaced by stand-ins (required for now)."
    ),
    max_ticks: int = typer.Option(1000, "--max-ticks", min=1, help="Stop after this many ticks."),
    substitute: list[str] = typer.Option(
        [], "--substitute", "-s", help="NODE=REPLACEMENT, e.g. Perceive=AlwaysSuccess or Approach=Running:3."
    ),
    outcome: list[str] = typer.Option(
        [], "--outcome", help="NAME=success, NAME=failure[:REASON] or NAME=running:N (leaf type, node name or path)."
    ),
    random_seed: int | None = typer.Option(
        None, "--random", help="Draw each robot leaf's outcome per attempt from this seed (success or a reason)."
    ),
    tick_hz: float = typer.Option(100.0, "--tick-hz", help="Simulated ticks per second."),
    as_json: bool = typer.Option(
        False, "--json", help="Print one JSON object: status, ticks, blackboard, walk (per tick, the statuses)."
    ),
    leaves: list[str] = leaves_option(),
    camera: str | None = typer.Option(
        None, "--camera", help="Run Perceive, PerceiveAll and PlanGrasp for real on this RealSense recording (one "
        "frame per capture) or device[:SERIAL], the arm at home; every other robot leaf stays a stand-in."
    ),
    calibration: Path | None = typer.Option(None, "--calibration", help="With --camera: the camera's calibration."),
    set_: list[str] = typer.Option([], "--set", help="Blackboard entry KEY=VALUE before the first tick."),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Tick a tree with a simulated clock until it finishes, every robot leaf replaced by a stand-in (SUCCESS
    unless --outcome or --random say otherwise); print the statuses of the nodes each tick walked; exit 0 on
    SUCCESS, 1 otherwise. With --camera the perception leaves run on a camera's frames."""
    from bt_grasp.behaviours.stand_ins import RobotStandIns
    from bt_grasp.clock import ManualClock
    from bt_grasp.episode.request import parse_assignments
    from bt_grasp.tree.dry_run import DryRunPlan, format_walk, known_reason_names, load_dry, parse_outcome, run_dry
    from bt_grasp.tree.node import BtStatus
    from bt_grasp.tree.values import display

    _show_tree_warnings()
    try:
        if not dry:
            raise InputError("--dry", "only dry runs exist here; `bt-grasp run` runs trees with the robot")
        if not tick_hz > 0:
            raise InputError("--tick-hz", f"must be positive, got {tick_hz}")
        clock = ManualClock()
        registry, catalog = tree_registry(leaves, no_plugins, plugins), RobotStandIns()
        rules = tuple(parse_outcome(text) for text in outcome)
        plan = DryRunPlan(rules, random_seed, catalog, known_reason_names(registry))
        entries = parse_assignments(set_)
        substitutions = _parse_substitutions(substitute)
        if calibration is not None and camera is None:
            raise InputError("--calibration", "is the camera's calibration: give it with --camera")
        if camera is None:
            tree = load_dry(file, registry, plan, substitutions=substitutions, clock=clock)
            for key, value in entries.items():
                tree.root_blackboard.set(key, value)
            result = run_dry(tree, clock, max_ticks, 1.0 / tick_hz)
        else:
            from bt_grasp.sensing.dry_camera import dry_run_on_camera
            from bt_grasp.sensing.source_spec import parse_camera_option

            result = dry_run_on_camera(file, registry, plan, parse_camera_option(camera), calibration, clock,
                                       max_ticks, 1.0 / tick_hz, substitutions=substitutions, entries=entries)
    except InputError as exc:
        raise _fail(exc) from None
    status = result.status
    if as_json:  # typed: integers and reals stay numbers
        from bt_grasp.recording.jsonable import to_jsonable

        blackboard = {k: to_jsonable(v) for k, v in result.blackboard.items()}
        walk = [tick.as_json() for tick in result.walk]
        typer.echo(json.dumps({"status": status.value, "ticks": result.ticks, "blackboard": blackboard, "walk": walk}))
    else:  # as BT.CPP prints values: a real with six decimals
        finished = "" if status.completed else f" (not finished after {result.ticks} ticks)"
        typer.echo(f"{status.value} after {result.ticks} ticks{finished}")
        for key, entry in result.blackboard.items():
            text = display(entry)
            typer.echo(f"  {key} = {text if len(text) <= 100 else text[:97] + '...'}")
        for line in format_walk(result.walk):
            typer.echo(line)
    raise typer.Exit(0 if status is BtStatus.SUCCESS else 1)


@tree_app.command("models")
def models_cmd(
    out: Path | None = typer.Option(None, "--out", help="Write the XML here instead of printing it."),
    include_builtins: bool = typer.Option(
        False, "--builtins", help="Also describe BT.CPP's built-in nodes (Groot2 knows them already)."
    ),
    only_plugins: bool = typer.Option(
        False, "--only-plugins", help="Only the nodes plugins registered (installed ones and --leaves), none of "
        "bt_grasp's own."
    ),
    leaves: list[str] = leaves_option(),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Write the TreeNodesModel of bt_grasp's nodes and the plugins' (ports, types, defaults), for Groot2's
    palette."""
    from bt_grasp.tree.builtins import builtin_names
    from bt_grasp.tree.formats.models import tree_nodes_model

    try:
        registry = tree_registry(leaves, no_plugins, plugins)
    except InputError as exc:
        raise _fail(exc) from None
    builtins = builtin_names()
    specs = [s for s in registry.specs()
             if (s.name in registry.origins if only_plugins else include_builtins or s.name not in builtins)]
    text = tree_nodes_model(specs)
    if out is None:
        typer.echo(text, nl=False)
        return
    try:
        write_output_file(out, text, "--out", example="models.xml")
    except InputError as exc:
        raise _fail(exc) from None
    typer.echo(f"wrote {len(specs)} node models to {out}")


def register(app: typer.Typer) -> None:
    """Add the ``tree`` command group to ``app``."""
    app.add_typer(tree_app, name="tree")
