"""`bt-grasp bench ...`: benchmarks. `plan` runs the motion-planning benchmark (bt_grasp.bench.plan).

The group lives here; each benchmark's logic lives in its own package.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from bt_grasp.cli.choices import MOUNT_LIST, Mount, PlannerChoice, TaskChoice
from bt_grasp.process.environment import machine_description

PLAN_BUDGET_DEFAULT = 40_000  # = PlannerOptions().max_state_checks (kept literal: the CLI imports lazily)

bench_app = typer.Typer(
    help="Developer benchmarks: measurements of bt_grasp itself (planning, perception, the simulator, the tree, "
    "logging, the task suite). To evaluate a tree: `bt-grasp eval run --tree T --scene S --seeds N` (the one "
    "evaluation entry point; docs/campaigns.md says why each command here is not one).",
    no_args_is_help=True,
)

#: ``bench --help``'s two panels. Episode benchmarks run whole seeded episodes, as ``eval run`` does, but they
#: measure bt_grasp (planning per pick, the whole task suite at once, campaign throughput) in one process and
#: keep no results file; micro-benchmarks measure one part. Neither is a way to evaluate a tree.
EPISODE_BENCHMARKS = "Episode benchmarks (developer; to evaluate a tree: eval run --tree T --scene S --seeds N)"
MICRO_BENCHMARKS = "Micro-benchmarks (developer: one part of bt_grasp measured)"


@bench_app.command("plan", rich_help_panel=MICRO_BENCHMARKS)
def plan(
    problems: int = typer.Option(60, "--problems", min=1, help="Number of tabletop problems."),
    seed: int = typer.Option(0, "--seed", help="Seed of the problem set (same seed, same problems)."),
    planner: PlannerChoice = typer.Option(PlannerChoice.RRTConnect, "--planner", help="OMPL planner."),
    budget: int = typer.Option(PLAN_BUDGET_DEFAULT, "--budget", min=1,
                               help="The search's work budget per problem: state validity checks."),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene", help="Scene file (table, mount)."),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
    export: Path = typer.Option(None, "--export", help="Also write the problems as JSON (for tools/)."),
) -> None:
    """Plan a fixed seeded set of tabletop problems: success rate, planning/IK/trajectory times."""
    from bt_grasp.bench.plan import make_problems, run_plan_bench
    from bt_grasp.motion.planner import PlannerOptions
    from bt_grasp.scene.format import load_scene

    config = load_scene(scene)
    options = PlannerOptions(planner=planner.value, max_state_checks=budget)
    if export is not None:
        export.write_text(json.dumps([p.to_json() for p in make_problems(config, problems, seed)], indent=1))
    report = run_plan_bench(config, problems, seed, options)
    summary = report.summary()
    summary["machine"] = machine_description()
    if as_json:
        typer.echo(json.dumps(summary))
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"bt-grasp bench plan: {problems} problems, seed {seed}, {planner}")
    table.add_column("metric")
    table.add_column("value", justify="right")
    rows = [
        ("success rate", f"{summary['success_rate']:.1%}"),
        ("success over feasible (labelled) problems",
         "n/a (unlabelled problem set)" if summary["success_over_feasible"] is None
         else f"{summary['success_over_feasible']:.1%} of {summary['feasible_problems']}"),
        ("plan time median (IK + search + re-check)", f"{summary['plan_ms_median']:.1f} ms"),
        ("plan time p95", f"{summary['plan_ms_p95']:.1f} ms"),
        ("IK time median", f"{summary['ik_ms_median']:.2f} ms"),
        ("trajectory (ruckig) time median", f"{summary['traj_ms_median']:.2f} ms"),
        ("joint path length median", f"{summary['path_length_rad_median']:.2f} rad"),
        ("trajectory duration median", f"{summary['traj_duration_s_median']:.2f} s"),
        ("straight line free (no search)", f"{summary['direct_fraction']:.0%}"),
        ("statuses", ", ".join(f"{k} {v}" for k, v in summary["statuses"].items())),
        ("machine", str(summary["machine"])),
    ]
    for name, value in rows:
        table.add_row(name, value)
    Console().print(table)


@bench_app.command("perception", rich_help_panel=MICRO_BENCHMARKS)
def perception(
    scenes: int = typer.Option(100, "--scenes", min=1, help="Number of random tabletop scenes."),
    seed: int = typer.Option(0, "--seed", help="Seed of the scene set (same seed, same scenes)."),
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene", help="Base scene (table, camera)."),
    calibration: bool = typer.Option(True, "--calibration/--no-calibration",
                                     help="Also judge hand-eye calibration (both mounts, noise on/off)."),
    noise_sweep: bool = typer.Option(False, "--noise-sweep",
                                     help="Sweep the sensor noise (1x-4x the default stereo error) instead."),
    adapt: bool = typer.Option(True, "--adapt/--fixed-thresholds",
                               help="With --noise-sweep: perception adapts to the measured noise (default) or not."),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
) -> None:
    """Perception accuracy against the simulator's truth: detection rate, centroid/yaw error, timings."""
    from bt_grasp.bench.noise import run_noise_sweep
    from bt_grasp.bench.perception import run_perception_bench
    from bt_grasp.bench.sim_backend import SimBenchBackend

    if noise_sweep:
        summary = run_noise_sweep(scenes, seed, backend=SimBenchBackend(scene), adapt=adapt)
    else:
        summary = run_perception_bench(scenes, seed, backend=SimBenchBackend(scene), calibrate=calibration)
    summary["machine"] = machine_description()
    text = json.dumps(_nan_to_null(summary), allow_nan=False)  # an empty statistic (NaN) prints as null
    if as_json:
        typer.echo(text)
        return
    from rich.console import Console

    Console().print_json(text)


def _nan_to_null(value: object) -> object:
    """``value`` with every NaN float as None: JSON has no NaN (JavaScript's JSON.parse refuses the token)."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {k: _nan_to_null(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_nan_to_null(v) for v in value]
    return value


@bench_app.command("tasks", rich_help_panel=EPISODE_BENCHMARKS)
def tasks(
    seeds: int = typer.Option(10, "--seeds", min=1, help="Episodes per task (seeds first-seed .. +N-1)."),
    first_seed: int = typer.Option(0, "--first-seed", help="The first seed."),
    task: list[TaskChoice] = typer.Option(
        [], "--task", help="Only this task (repeatable; default: every shipped task).", show_default=False
    ),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
) -> None:
    """Run every shipped task (trees/T.xml on scenes/T.yaml, judged by the scene's goal) over N seeds in one
    process; print the success rate per task and why the failures failed. (A developer benchmark: for one task as
    a resumable campaign, `bt-grasp eval run --tree trees/T.xml --scene scenes/T.yaml --seeds N`.)"""
    from bt_grasp.bench.tasks import TASKS, run_task_bench

    known = {t.name: t for t in TASKS}
    chosen = [known[n.value] for n in task] if task else list(TASKS)
    from rich.console import Console

    err = Console(stderr=True)

    def progress(name: str, seed: int, ok: bool | None, why: str) -> None:  # stderr: stdout stays one JSON object
        outcome = "success" if ok else ("not run: " if ok is None else "FAILURE ") + why
        err.print(f"{name} seed {seed}: {outcome}", highlight=False, markup=False)

    figures = run_task_bench(chosen, seeds, first_seed, progress=progress)
    rows = [f.summary() for f in figures]
    summary = {"tasks": rows, "machine": machine_description()}
    if as_json:
        typer.echo(json.dumps(summary))
        return
    from rich.table import Table

    table = Table(title=f"bt-grasp bench tasks: {seeds} seed(s) per task from seed {first_seed}")
    for column in ("task", "success", "rate", "sim s (median)", "wall s (median)", "failures"):
        table.add_column(column, justify="left" if column in ("task", "failures") else "right")
    for f in rows:
        failures = ", ".join(f"{k} x{v}" for k, v in f["failures"].items()) or "-"
        strict = f["successes_upright_set_down"]
        also = "" if strict is None else f" ({strict} set down upright)"  # a clear-into goal as judged before
        table.add_row(f["task"], f"{f['successes']}/{f['episodes']}{also}", f"{f['success_rate']:.0%}",
                      f"{f['sim_time_s_median']:.1f}", f"{f['wall_time_s_median']:.1f}", failures)
    Console().print(table)
    for f in rows:
        for seed, problem in f["unplaced_seeds"].items():
            Console().print(f"{f['task']} seed {seed} not run: {problem} (the scene's objects do not fit at this seed)",
                            highlight=False, markup=False)
    Console().print(f"machine: {summary['machine']}")


@bench_app.command("follow", rich_help_panel=MICRO_BENCHMARKS)
def follow(
    seeds: int = typer.Option(3, "--seeds", min=0, help="Tracking episodes per mount and belt speed (0: none)."),
    speeds: str = typer.Option("0.02,0.05,0.10", "--speeds", help="Belt speeds, m/s, comma-separated."),
    mounts: str = typer.Option(
        "eye-to-hand,eye-in-hand", "--mounts", parser=MOUNT_LIST, autocompletion=MOUNT_LIST.complete,
        metavar=MOUNT_LIST.metavar, help="Camera mounts, comma-separated."
    ),
    pick_seeds: int = typer.Option(0, "--pick-seeds", min=0,
                                   help="Also pick from the conveyor this many seeds per speed (eye-to-hand)."),
    pick_mount: Mount = typer.Option(Mount.EYE_TO_HAND, "--pick-mount", help="Camera mount of the pick episodes."),
    first_seed: int = typer.Option(0, "--first-seed", min=0, help="First seed of the pick episodes."),
    table: bool = typer.Option(False, "--table", help="Issue 45's rows instead of --speeds' picks: eye-to-hand at "
                               "10, 20, 30, 50 cm/s, eye-in-hand at 20, household at 30, picks per minute into a "
                               "bin at 30 cm/s; --pick-seeds seeds each (default 4)."),
    rows: str = typer.Option("", "--rows", help="With --table: only the rows whose names contain one of these "
                             "comma-separated words (e.g. 'eye-in-hand,household')."),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
) -> None:
    """Visual following on the conveyor: tracking error against the simulator's truth, and the pick rate."""
    from bt_grasp.bench.follow import ISSUE_ROWS, issue_table, run_conveyor_pick_bench, run_tracking_bench
    from bt_grasp.errors import InputError

    try:
        speed_list = [float(v) for v in speeds.split(",") if v.strip()]
    except ValueError:
        raise InputError("--speeds", f"expected numbers separated by commas, got '{speeds}'") from None
    mount_list = mounts.split(",")  # checked by the parser (MOUNT_LIST): each one a key of SCENES
    only = [w.strip() for w in rows.split(",") if w.strip()]
    if only and not table:
        raise InputError("--rows", "selects rows of --table; add --table")
    unknown = [w for w in only if not any(w in what for what, *_ in ISSUE_ROWS)]
    if unknown:
        raise InputError("--rows", f"no row of the table is named by '{unknown[0]}' (rows: "
                         f"{'; '.join(what for what, *_ in ISSUE_ROWS)})")
    repo = Path.cwd()
    say = None if as_json else typer.echo
    summary: dict[str, object] = {}
    if seeds:
        summary["tracking"] = run_tracking_bench(repo, speed_list, seeds, mount_list, progress=say)
    if table:
        summary["table"] = issue_table(repo, pick_seeds or 4, first_seed, only, progress=say)
    elif pick_seeds:
        summary["picks"] = [run_conveyor_pick_bench(repo, v, pick_seeds, pick_mount.value, first_seed=first_seed,
                                                    progress=say) for v in speed_list]
    summary["machine"] = machine_description()
    typer.echo(json.dumps(summary, indent=None if as_json else 1))
    if table and not as_json:
        for row in summary["table"]:  # type: ignore[attr-defined]
            failures = ", ".join(f"{k} x{v}" for k, v in row["failures"].items()) or "-"
            rate = f", {row['picks_per_min_median']:.1f} picks/min (median)" if "picks_per_min_median" in row else ""
            typer.echo(f"{row['row']}: {row['successes']}/{row['episodes']}{rate}; failures: {failures}")


def register(app: typer.Typer) -> None:
    app.add_typer(bench_app, name="bench")
