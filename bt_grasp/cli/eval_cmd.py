"""`bt-grasp eval`: run an evaluation campaign on local workers or a Ray cluster, export it, report on it."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer
from rich.console import Console
from rich.markup import escape

from bt_grasp.cli.plugin_option import leaves_option

if TYPE_CHECKING:  # the campaign package is imported when a campaign runs, not for --help
    from bt_grasp.campaign.runner import EpisodeError, Progress

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


def progress_printer(console: Console) -> Any:
    from bt_grasp.campaign.runner import EpisodeError

    def show(progress: Progress, item: dict[str, Any] | EpisodeError | None) -> None:
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
        console.print(f"{head}  {what}", highlight=False, soft_wrap=True)

    return show


@eval_app.command("run")
def run(
    campaign_file: Path = typer.Argument(..., help="Campaign YAML file."),
    out: Path = typer.Option(..., "--out", help="Folder for the results (NAME.jsonl) and kept MCAP logs."),
    workers: int = typer.Option(0, "--workers", min=0, help="Local worker processes (0 = one per core)."),
    ray: str | None = typer.Option(
        None, "--ray", metavar="ADDRESS",
        help="Run on a Ray cluster: its head's host:port, 'auto' (the cluster this machine belongs to) or 'local' "
        "(start a throw-away one here).",
    ),
    keep_logs: str = typer.Option(
        "failures", "--keep-logs", help="Which episodes keep their MCAP log: failures|all|none."
    ),
    parquet: bool = typer.Option(True, "--parquet/--no-parquet", help="Also export the results as NAME.parquet."),
    leaves: list[str] = leaves_option(),
) -> None:
    """Run every episode of a campaign that has no result yet (so running it again resumes it)."""
    from bt_grasp.campaign.backend import warm_backend
    from bt_grasp.campaign.results import export_parquet, read_rows, results_path
    from bt_grasp.campaign.runner import run_campaign
    from bt_grasp.campaign.spec import load_campaign
    from bt_grasp.campaign.worker import KeepLogs
    from bt_grasp.errors import InputError

    try:
        keep = KeepLogs(keep_logs)
    except ValueError:
        raise InputError("--keep-logs", f"expected failures, all or none, got '{keep_logs}'") from None
    # plugin files as absolute paths: every worker loads them (on a Ray cluster, the same path on each node)
    plugins = tuple(str(Path(v).absolute()) if v.endswith(".py") else v for v in leaves)
    campaign = load_campaign(campaign_file, leaves=plugins)
    log_dir = out / "logs"
    if ray is not None:
        from bt_grasp.campaign.ray_engine import RayEngine

        def engine() -> Any:
            return RayEngine(ray, workers or None, warm_backend, log_dir.resolve(), keep)
    else:
        from bt_grasp.campaign.local import LocalEngine, default_workers

        def engine() -> Any:
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

    typer.echo(str(export_parquet(read_rows(results), out)))


@eval_app.command("report")
def report(
    results: Path = typer.Argument(..., help="A campaign's results file (NAME.jsonl)."),
    out: Path = typer.Option(..., "--out", help="HTML file to write; its PNG figures go beside it."),
    compare: Path | None = typer.Option(None, "--compare", help="A second results file to compare with (B)."),
) -> None:
    """A self-contained HTML report (no network needed) with success rates, failures, times, retries."""
    from bt_grasp.campaign.report import build_report

    written = build_report(results, out, compare)
    typer.echo(f"{written[0]}  (figures: {written[1].parent})")


def register(app: typer.Typer) -> None:
    app.add_typer(eval_app, name="eval")
