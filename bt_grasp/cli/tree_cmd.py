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
    from bt_grasp.clock import ManualClock
    from bt_grasp.tree.dry_run import DryRunResult
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
    """One line per problem (``tree validate`` and ``tree run`` name every unknown node, each at its line)."""
    lines = getattr(exc, "lines", None) or (exc.message,)
    for line in lines:
        typer.echo(f"{ERROR_PREFIX}{shown(line, newlines=False)}", err=True)  # control characters shown, never obeyed
    return typer.Exit(exc.exit_code)


def _show_tree_warnings() -> None:
    """The tree package's warnings as one line each (``bt-grasp: warning: ...``), nothing below them."""
    from bt_grasp.cli.tree_warnings import show_tree_warnings

    show_tree_warnings()


@tree_app.command("validate")
def validate_cmd(
    file: Path = typer.Argument(..., help="XML or YAML tree file."),
    scene: Path | None = typer.Option(
        None, "--scene", help="Also check the tree against this scene file: a fixture it lacks is an error (with the "
        "closest name), a colour or class none of its objects has a warning."
    ),
    leaves: list[str] = leaves_option(),
    no_plugins: bool = no_plugins_option(),
    plugins: list[str] = plugin_option(),
) -> None:
    """Check a tree file completely (nodes, ports, scripts, includes, subtrees) without running it; every unknown
    node is named, each at its file and line."""
    from bt_grasp.tree.loader import load_tree

    _show_tree_warnings()
    try:
        tree = load_tree(file, tree_registry(leaves, no_plugins, plugins))
        from bt_grasp.behaviours.objects import check_detector_classes

        check_detector_classes(tree.nodes())  # a SelectObject's class against the tree's learned models
        notes: list[str] = []
        if scene is not None:
            from bt_grasp.behaviours.library import check_tree_against_scene, scene_notes
            from bt_grasp.scene.format import load_scene

            loaded = load_scene(scene)
            check_tree_against_scene(tree.nodes(), loaded)
            notes = scene_notes(tree.nodes(), loaded, str(scene))
    except InputError as exc:
        raise _fail(exc) from None
    for note in notes:
        typer.echo(f"bt-grasp: warning: {shown(note, newlines=False)}", err=True)
    count = sum(1 for _ in tree.nodes())
    fits = f", fits {scene}" if scene is not None else ""
    typer.echo(f"{file}: OK ({count} nodes, main tree {tree.main_tree}{fits})")


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
        [], "--substitute", "-s", help="NODE=REPLACEMENT, e.g. Perceive=AlwaysSuccess or Approach=Running:3 (a "
        "pattern that replaces no leaf is an error)."
    ),
    outcome: list[str] = typer.Option(
        [], "--outcome", help="NAME=OUTCOME[,OUTCOME...], one per call, the last repeating; each success, "
        "failure[:REASON] or running:N[:failure[:REASON]]. NAME: a leaf's type or name, or a pattern (* ?) over its "
        "full path."
    ),
    output_port: list[str] = typer.Option(
        [], "--output-port", help="NAME.PORT=VALUE[,VALUE...]: what a stand-in writes to that output port, call by "
        "call (else its type's default)."
    ),
    random_seed: int | None = typer.Option(
        None, "--random", help="Draw each robot leaf's outcome per attempt from this seed (success or a reason)."
    ),
    tick_hz: float = typer.Option(100.0, "--tick-hz", help="Simulated ticks per second."),
    nodes_model: list[Path] = typer.Option(
        [], "--nodes-model", help="A TreeNodesModel file (Groot2's, e.g. Nav2's nav2_tree_nodes.xml): a stand-in for "
        "each action and condition it declares that no plugin provides (the tree's own models count too)."
    ),
    rules_file: Path | None = typer.Option(
        None, "--substitution-rules", help="BehaviorTree.CPP's substitution-rule JSON (TestNodeConfigs, "
        "SubstitutionRules), read as loadSubstitutionRuleFromJSON reads it; async_delay in simulated ms."
    ),
    scene: Path | None = typer.Option(
        None, "--scene", help="Check the tree against this scene and take fixture poses (FixturePose) from it."
    ),
    export_btlog: Path | None = typer.Option(
        None, "--export-btlog", help="Also write the walk as a Groot2 .btlog file (as replay --export-btlog does)."
    ),
    as_json: bool = typer.Option(
        False, "--json", help="Print one JSON object: status, ticks, blackboard, walk (per tick), transitions."
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
    """Tick a tree with a simulated clock until it finishes, its leaves stood in for where no code runs them (robot
    leaves; a TreeNodesModel's nodes; BT.CPP substitution rules), steered call by call (--outcome); print every
    status change in order as BT.CPP's StdCoutLogger does (the full path for the name); exit 0 on SUCCESS, 1
    otherwise. With --camera the perception leaves run on a camera's frames."""
    from bt_grasp.clock import ManualClock

    _show_tree_warnings()
    try:
        if not dry:
            raise InputError("--dry", "only dry runs exist here; `bt-grasp run` runs trees with the robot")
        if not tick_hz > 0:
            raise InputError("--tick-hz", f"must be positive, got {tick_hz}")
        if calibration is not None and camera is None:
            raise InputError("--calibration", "is the camera's calibration: give it with --camera")
        if export_btlog is not None:
            from bt_grasp.files.output_files import check_output_file

            check_output_file(export_btlog, "--export-btlog", example="run.btlog", inputs=(file,))
        clock = ManualClock()
        registry = tree_registry(leaves, no_plugins, plugins)
        result = _dry_run(file, registry, clock, max_ticks, 1.0 / tick_hz, outcome, output_port, random_seed,
                          substitute, nodes_model, rules_file, scene, camera, calibration, set_)
        if export_btlog is not None:
            _write_btlog(export_btlog, result)
    except InputError as exc:
        raise _fail(exc) from None
    _print_dry_run(result, as_json, export_btlog)


def _dry_run(file: Path, registry: NodeRegistry, clock: ManualClock, max_ticks: int, dt_s: float,
             outcome: list[str], output_port: list[str], random_seed: int | None, substitute: list[str],
             nodes_model: list[Path], rules_file: Path | None, scene: Path | None, camera: str | None,
             calibration: Path | None, set_: list[str]) -> DryRunResult:
    """Load and tick the tree as ``tree run --dry`` does (every argument checked first: InputError)."""
    from bt_grasp.behaviours.stand_ins import RobotStandIns
    from bt_grasp.episode.request import parse_assignments
    from bt_grasp.tree.dry_run import DryRunPlan, known_reason_names, load_dry, run_dry
    from bt_grasp.tree.model_stand_ins import read_nodes_model
    from bt_grasp.tree.outcomes import parse_outcome, parse_output
    from bt_grasp.tree.rules_file import read_rules_file

    loaded_scene = None
    if scene is not None:
        from bt_grasp.behaviours.library import check_tree_against_scene
        from bt_grasp.scene.format import load_scene
        from bt_grasp.tree.loader import load_tree

        loaded_scene = load_scene(scene)
        check_tree_against_scene(load_tree(file, registry).nodes(), loaded_scene)  # as `run` refuses it
    plan = DryRunPlan(tuple(parse_outcome(text) for text in outcome), random_seed, RobotStandIns(loaded_scene),
                      known_reason_names(registry), tuple(parse_output(text) for text in output_port))
    entries = parse_assignments(set_)
    substitutions = _parse_substitutions(substitute)
    models = [model for path in nodes_model for model in read_nodes_model(path)]
    rules = read_rules_file(rules_file) if rules_file is not None else None
    if camera is None:
        tree = load_dry(file, registry, plan, substitutions=substitutions, clock=clock, rules=rules, models=models)
        for key, value in entries.items():
            tree.root_blackboard.set(key, value)
        return run_dry(tree, clock, max_ticks, dt_s)
    if rules is not None or models:
        raise InputError("--camera", "runs bt_grasp's perception leaves for real; give --substitution-rules and "
                         "--nodes-model without it")
    from bt_grasp.sensing.dry_camera import dry_run_on_camera
    from bt_grasp.sensing.source_spec import parse_camera_option

    return dry_run_on_camera(file, registry, plan, parse_camera_option(camera), calibration, clock,
                             max_ticks, dt_s, substitutions=substitutions, entries=entries)


def _write_btlog(path: Path, result: DryRunResult) -> None:
    """The walk as Groot2's .btlog, with ``replay --export-btlog``'s writer (times: simulated µs from tick 1)."""
    import time

    from bt_grasp.recording.btlog import Transition, write_walk_btlog
    from bt_grasp.tree.introspect import tree_structure

    assert result.tree is not None
    moves = [Transition(t.time_ns // 1000, t.uid, t.new) for t in result.transitions]
    write_walk_btlog(path, tree_structure(result.tree.root), result.tree.main_tree, time.time_ns(), moves)


def _print_dry_run(result: DryRunResult, as_json: bool, btlog: Path | None) -> None:
    from bt_grasp.tree.node import BtStatus
    from bt_grasp.tree.values import display
    from bt_grasp.tree.walk import stdout_lines

    status = result.status
    if as_json:  # typed: integers and reals stay numbers
        from bt_grasp.recording.jsonable import to_jsonable

        blackboard = {k: to_jsonable(v) for k, v in result.blackboard.items()}
        typer.echo(json.dumps({
            "status": status.value, "ticks": result.ticks, "blackboard": blackboard,
            "walk": [tick.as_json() for tick in result.walk],
            "transitions": [move.as_json() for move in result.transitions],
        }))
    else:  # as BT.CPP prints values: a real with six decimals
        finished = "" if status.completed else f" (not finished after {result.ticks} ticks)"
        typer.echo(f"{status.value} after {result.ticks} ticks{finished}")
        for key, entry in result.blackboard.items():
            text = display(entry)
            typer.echo(f"  {key} = {text if len(text) <= 100 else text[:97] + '...'}")
        for line in stdout_lines(result.walk, result.transitions):
            typer.echo(shown(line, newlines=False))
        if btlog is not None:
            typer.echo(f"wrote {len(result.transitions)} transitions to {shown(str(btlog), newlines=False)}")
    raise typer.Exit(0 if status is BtStatus.SUCCESS else 1)


@tree_app.command("stubs")
def stubs_cmd(
    model_file: Path = typer.Argument(..., help="A TreeNodesModel file (Groot2's; e.g. Nav2's nav2_tree_nodes.xml), "
                                      "or a tree file holding one."),
    out: Path = typer.Option(..., "--out", "-o", help="The plugin file to write (FILE.py)."),
    force: bool = typer.Option(False, "--force", help="Overwrite OUT if it exists."),
) -> None:
    """Write a plugin file of typed stand-ins for the model's actions and conditions, in bt_grasp's node API (each
    succeeds, writing its outputs' defaults): it loads with --leaves FILE.py and ticks; replace each update()."""
    from bt_grasp.tree.model_stand_ins import read_nodes_model
    from bt_grasp.tree.stubs import stubs_text

    try:
        if out.suffix != ".py":
            raise InputError("--out", f"{out} must end in .py (a plugin file --leaves loads)")
        check_output_file(out, "--out", example="my_nodes.py", inputs=(model_file,))
        if out.exists() and not force:
            raise InputError(out, "exists; pass --force to overwrite it")
        text, count = stubs_text(read_nodes_model(model_file), model_file.name)
        if count == 0:
            raise InputError(model_file, "declares no action or condition to stand in for")
        write_output_file(out, text, "--out", example="my_nodes.py")
    except InputError as exc:
        raise _fail(exc) from None
    typer.echo(f"wrote {count} stand-in{'s' * (count != 1)} to {out} (load it with --leaves {out})")


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
