"""`bt-grasp eval`: run an evaluation campaign on local workers or a Ray cluster, export it, report on it."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.console import Console
from rich.markup import escape

from bt_grasp.cli.plugin_option import leaves_option
from bt_grasp.defaults import DEFAULT_MAX_TICKS

if TYPE_CHECKING:  # the campaign package is imported when a campaign runs, not for --help
    from bt_grasp.campaign.rows import ResultRow
    from bt_grasp.campaign.runner import Engine, EpisodeError, Progress

eval_app = typer.Typer(
    help="Evaluation campaigns: trees x scenes x seeds x fault plans, resumable.", no_args_is_help=True
)


def _duration(seconds: float | None) -> str:
    if seconds is None:
        return "?"
    seconds = int(seconds)
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h}h{m:02d}m" if h else (f"{m}m{s:02d}s" if m else f"{s}s")


def progress_printer(console: Console) -> Callable[[Progress, ResultRow | EpisodeError | None], None]:
    from bt_grasp.campaign.runner import EpisodeError

    def show(progress: Progress, item: ResultRow | EpisodeError | None) -> None:
        finished = progress.already + progress.done
        rate = progress.success_rate
        head = (
            f"[{finished}/{progress.total}] {progress.rate_per_min:5.1f} episodes/min  ETA {_duration(progress.eta_s)}"
            f"  success {'-' if rate is None else f'{100 * rate:.1f}%'}"
        )
        if item is None:
            resumed = f" ({progress.already} already done: resuming)" if progress.already else ""
            console.print(f"{progress.total} episodes{resumed}", highlight=False)
            return
        if isinstance(item, EpisodeError):
            what = f"[red]NOT FINISHED[/] {escape(item.episode.label())}: {escape(item.message)}"
        else:
            verdict = (
                "[green]ok[/]" if item["success"]
                else f"[red]FAIL[/] {escape(str(item['failure_reason']))} ({escape(str(item['failed_leaf']))})"
            )
            label = f"{Path(str(item['tree'])).stem}/{item['scene']}/seed{item['seed']}/{item['fault_plan']}"
            what = f"{escape(label)} {verdict}"
            for firing in item.get("faults") or []:
                if firing.get("target") is not None and firing.get("target_touched") is False:
                    what += f" [yellow](a fault pushed {escape(str(firing['target']))}: the tree never touched it)[/]"
        console.print(f"{head}  {what}", highlight=False, soft_wrap=True)

    return show


class KeepLogsChoice(StrEnum):
    """Which episodes keep their MCAP log (``bt_grasp.campaign.worker.KeepLogs``, kept literal: --help imports
    no campaign code)."""

    failures = "failures"
    all = "all"
    none = "none"


@eval_app.command("run")
def run(
    campaign_file: Path | None = typer.Argument(
        None, help="Campaign YAML file (docs/campaigns.md); or give --tree and --scene instead."
    ),
    trees: list[Path] = typer.Option(
        [], "--tree", help="Without a campaign file: the tree to evaluate (repeatable).", show_default=False
    ),
    scenes: list[Path] = typer.Option(
        [], "--scene", help="Without a campaign file: the scene to run it on (repeatable).", show_default=False
    ),
    seeds: int = typer.Option(10, "--seeds", min=1, help="Without a campaign file: seeded episodes per tree x scene."),
    first_seed: int = typer.Option(0, "--first-seed", min=0, help="Without a campaign file: the first seed."),
    max_ticks: int = typer.Option(
        DEFAULT_MAX_TICKS, "--max-ticks", min=1,
        help="Without a campaign file: each episode's tick limit (100 a simulated second).",
    ),
    name: str | None = typer.Option(
        None, "--name", help="Without a campaign file: the campaign's name (default: TREE-SCENE)."
    ),
    calibration: Path | None = typer.Option(
        None, "--calibration", help="Without a campaign file: the calibration YAML every episode loads (default: "
        "the file each scene names beside it; a campaign file says it with its 'calibration' key)."
    ),
    out: Path | None = typer.Option(
        None, "--out", help="Folder for the results (NAME.jsonl) and kept MCAP logs (default: out/NAME)."
    ),
    workers: int = typer.Option(0, "--workers", min=0, help="Local worker processes (0 = one per core)."),
    ray: str | None = typer.Option(
        None, "--ray", metavar="ADDRESS",
        help="Run on a Ray cluster: its head's host:port, 'auto' (the cluster this machine belongs to) or 'local' "
        "(start a throw-away one here). An address nobody answers on is refused within seconds.",
    ),
    keep_logs: KeepLogsChoice = typer.Option(
        KeepLogsChoice.failures, "--keep-logs", help="Which episodes keep their MCAP log."
    ),
    parquet: bool = typer.Option(True, "--parquet/--no-parquet", help="Also export the results as NAME.parquet."),
    leaves: list[str] = leaves_option(),
) -> None:
    """Evaluate: every episode of a campaign file, or of `--tree T --scene S --seeds N`, that has no result yet
    (so running it again resumes it)."""
    from bt_grasp.campaign.backend import warm_backend
    from bt_grasp.campaign.results import export_parquet, read_rows, results_path
    from bt_grasp.campaign.runner import run_campaign
    from bt_grasp.campaign.spec import load_campaign
    from bt_grasp.campaign.worker import KeepLogs
    from bt_grasp.errors import InputError

    keep = KeepLogs(keep_logs.value)
    if ray is not None:
        from bt_grasp.campaign.ray_engine import probe_address

        probe_address(ray)  # before anything else: an unreachable head is one sentence, within seconds
    # plugin files as absolute paths: every worker loads them (on a Ray cluster, the same path on each node)
    plugins = tuple(str(Path(v).absolute()) if v.endswith(".py") else v for v in leaves)
    from bt_grasp.files.output_files import check_output_folder

    if campaign_file is None:
        if not trees or not scenes:
            raise InputError("eval run", "give a campaign file, or --tree and --scene (e.g. `bt-grasp eval run "
                                         "--tree trees/pick.xml --scene scenes/tabletop.yaml --seeds 50`)")
        from bt_grasp.campaign.spec import check_options_inputs, options_campaign_path, write_options_campaign

        target = options_campaign_path(trees, scenes, name, out)
        out = target.parent
        check_output_folder(out, "--out")
        check_options_inputs(trees, scenes, calibration, max_ticks, plugins)  # as `run` checks them: nothing written
        with _undone_if_refused(target):  # a refusal from here on leaves nothing behind either
            campaign_file = write_options_campaign(trees, scenes, seeds, first_seed, name, out, max_ticks=max_ticks,
                                                   calibration=calibration)
            campaign = load_campaign(campaign_file, leaves=plugins, check_inputs=False)  # checked just above
    else:
        given = [flag for flag, value in (("--tree", trees), ("--scene", scenes), ("--name", name)) if value]
        if max_ticks != DEFAULT_MAX_TICKS:
            given.append("--max-ticks")
        if given:
            raise InputError(given[0], f"does not go with a campaign file; {campaign_file} already names the trees, "
                                       "scenes and seeds")
        if calibration is not None:
            raise InputError("--calibration", f"does not go with a campaign file; give {campaign_file} a "
                                              "'calibration' key (every scene) or a scene entry one")
        campaign = load_campaign(campaign_file, leaves=plugins)
        if out is None:
            out = Path("out") / campaign.name
    log_dir = out / "logs"
    check_output_folder(out, "--out")
    check_output_folder(log_dir, "--out")  # kept logs go in <out>/logs: never through a link elsewhere
    if ray is not None:
        from bt_grasp.campaign.ray_engine import RayEngine

        def engine() -> Engine:
            return RayEngine(ray, workers or None, warm_backend, log_dir.resolve(), keep)
    else:
        from bt_grasp.campaign.local import LocalEngine, default_workers

        def engine() -> Engine:
            return LocalEngine(workers or default_workers(), warm_backend, log_dir.resolve(), keep)

    console = Console(stderr=True)
    progress = run_campaign(campaign, out, engine, progress_printer(console))
    path = results_path(out, campaign.name)
    rows = read_rows(path)
    if parquet and rows:
        export_parquet(rows, path.with_suffix(".parquet"))
    ok = sum(1 for r in rows if r["success"])
    typer.echo(f"{len(rows)} episodes, {ok} succeeded ({progress.done} run now): {path}")


@eval_app.command("export")
def export(
    results: Path = typer.Argument(..., help="A campaign's results file (NAME.jsonl)."),
    out: Path = typer.Option(..., "--out", help="Parquet file to write."),
) -> None:
    """Export a results file to Parquet."""
    from bt_grasp.campaign.results import export_parquet, read_rows

    _writable_file(out, "Parquet", results)
    try:
        typer.echo(str(export_parquet(read_rows(results), out)))
    except OSError as exc:
        raise _cannot_write(out, exc) from None


@eval_app.command("report")
def report(
    results: Path = typer.Argument(..., help="A campaign's results file (NAME.jsonl)."),
    out: Path = typer.Option(..., "--out", help="HTML file to write; its PNG figures go beside it."),
    compare: Path | None = typer.Option(None, "--compare", help="A second results file to compare with (B)."),
) -> None:
    """A self-contained HTML report (no network needed) with success rates, failures, times, retries."""
    from bt_grasp.campaign.report import build_report, figure_folder
    from bt_grasp.files.output_files import check_output_folder

    _writable_file(out, "HTML", results, compare)
    check_output_folder(figure_folder(out), "--out", inputs=(results, compare))  # before any work
    try:
        written = build_report(results, out, compare)
    except OSError as exc:
        raise _cannot_write(out, exc) from None
    typer.echo(f"{written[0]}  (figures: {written[1].parent})")


@contextmanager
def _undone_if_refused(path: Path) -> Iterator[None]:
    """Writes ``path`` (and the folders above it that do not exist yet) inside the block; if the block is refused,
    removes what it wrote: a refused command leaves nothing behind. A file that was there before stays."""
    from bt_grasp.errors import BtGraspError

    existed = path.exists() or path.is_symlink()
    made = [p for p in path.parents if not p.exists()]  # deepest first
    try:
        yield
    except BtGraspError:
        if not existed:
            path.unlink(missing_ok=True)
        for folder in made:
            try:
                folder.rmdir()  # only when empty
            except OSError:
                break
        raise


def _writable_file(out: Path, kind: str, *inputs: Path | None) -> None:
    """``--out`` names a file that can be written (``bt_grasp.files.output_files``), checked before any work: a folder
    was a traceback (issue 24); a link, a FIFO, a device or the results file itself are refused too."""
    from bt_grasp.files.output_files import check_output_file

    check_output_file(out, "--out", example="report.html" if kind == "HTML" else "results.parquet", inputs=inputs)


def _cannot_write(out: Path, exc: OSError) -> Exception:
    from bt_grasp.errors import InputError

    return InputError("--out", f"cannot write '{exc.filename or out}': {(exc.strerror or str(exc)).lower()}")


def register(app: typer.Typer) -> None:
    app.add_typer(eval_app, name="eval")
