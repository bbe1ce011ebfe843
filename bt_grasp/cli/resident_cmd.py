"""`bt-grasp resident status|stop`: look at or stop this user's warm resident process."""

from __future__ import annotations

import typer

resident_app = typer.Typer(help="This user's warm resident process (what `run --resident` uses).",
                           no_args_is_help=True)


@resident_app.command("status")
def status() -> None:
    """Say whether a resident process serves this user's folder, and its pid (exit 0 running, 1 not)."""
    from bt_grasp.resident.client import resident_status

    pid, folder = resident_status()
    if pid is None:
        typer.echo(f"no resident process ({folder})")
        raise typer.Exit(1)
    typer.echo(f"resident process {pid} serves {folder}")


@resident_app.command("stop")
def stop() -> None:
    """Stop this user's resident process if one runs."""
    from bt_grasp.resident.client import stop_resident
    from bt_grasp.resident.protocol import home

    pid = stop_resident()
    typer.echo(f"stopped resident process {pid}" if pid is not None else f"no resident process ({home()})")


def register(app: typer.Typer) -> None:
    app.add_typer(resident_app, name="resident")
