"""`bt-grasp init DIR`: write a starter project (a tree, a scene, a calibration, a campaign) into a folder."""

from __future__ import annotations

import shlex
from pathlib import Path

import typer


def init(
    folder: Path = typer.Argument(..., metavar="DIR", help="Folder to write the project into (made if missing)."),
    force: bool = typer.Option(False, "--force", help="Overwrite the project's files if DIR already holds them."),
) -> None:
    """Write a starter project into DIR: a task tree, its scene, a calibration and a campaign, which run as
    written (the tree's includes come from bt_grasp's shipped library)."""
    from bt_grasp.episode.starter import STARTER_FILES, write_starter

    written = write_starter(folder, force=force)
    typer.echo(f"wrote {len(written)} files into {folder}:")
    for path in written:
        typer.echo(f"  {path.name:<17} {STARTER_FILES[path.name]}")
    q = {name: shlex.quote(str(folder / name)) for name in (*STARTER_FILES, "run.mcap", "results")}
    typer.echo("next:")
    typer.echo(f"  bt-grasp tree validate {q['task.xml']}")
    typer.echo(f"  bt-grasp run {q['task.xml']} --scene {q['scene.yaml']} --seed 0 --log {q['run.mcap']}")
    typer.echo(f"  bt-grasp replay {q['run.mcap']} --failures")
    typer.echo(f"  bt-grasp eval run {q['campaign.yaml']} --out {q['results']}")
    typer.echo(f"  bt-grasp eval report {shlex.quote(str(folder / 'results' / 'starter.jsonl'))} "
               f"--out {shlex.quote(str(folder / 'results' / 'report.html'))}")


def register(app: typer.Typer) -> None:
    app.command("init")(init)
