"""`bt-grasp calibrate --cell CELL`: hand-eye calibration on a real cell or a twin (parsing and printing only: the
procedure is ``bt_grasp.episode.cell_calibration``)."""

from __future__ import annotations

import json
import signal
import sys
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape

from bt_grasp.errors import InputError


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def calibrate_on_cell(cell: Path, out: Path | None, poses: int, seed: int, yes: bool, as_json: bool) -> None:
    from bt_grasp.cli.cell_run_options import ask
    from bt_grasp.episode.cell_calibration import calibrate_cell, calibration_target
    from bt_grasp.files.output_files import check_output_file

    target = calibration_target(cell)  # the cell names where its calibration goes
    if out is not None and out.resolve() != target:
        raise InputError("--out", f"with --cell the calibration is written where the cell file says ({target}); "
                         "drop --out or change the cell file's calibration key")
    check_output_file(target, "calibration", example="cell.calibration.yaml", inputs=(cell,))
    if not yes and not sys.stdin.isatty():
        raise InputError("--yes", "calibrating a real cell asks before the arm's first motion and standard input is "
                         "not a terminal: give --yes to confirm it in advance")
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    result = calibrate_cell(cell, poses, seed, None if yes else ask)
    run = result.run
    chosen = run.solution.chosen
    summary = {
        "cell": str(cell), "out": str(result.out), "ran_on": result.ran_on, "address": result.address,
        "method": run.solution.method, "samples": len(run.views), "visited": run.visited,
        "rejected": run.rejected, "residual_mm": round(chosen.residual_mm, 4),
        "residual_deg": round(chosen.residual_deg, 5), "reprojection_px": round(chosen.reprojection_px, 4),
        "per_method": {name: r.as_dict() for name, r in run.solution.per_method.items()},
        "elapsed_s": round(result.elapsed_s, 2),
    }
    if as_json:
        typer.echo(json.dumps(summary))
        return
    from rich.table import Table

    table = Table(title=f"hand-eye calibration on the {result.ran_on} at {result.address}: {len(run.views)} views "
                  f"of {run.visited} visited")
    for column in ("method", "scatter mm", "residual mm", "residual deg", "reproj px"):
        table.add_column(column, justify="right" if column != "method" else "left", no_wrap=column == "method")
    for name, r in run.solution.per_method.items():
        mark = " (chosen)" if name == run.solution.method else ""
        table.add_row(name + mark, f"{r.scatter_mm:.3f}", f"{r.residual_mm:.3f}", f"{r.residual_deg:.4f}",
                      f"{r.reprojection_px:.3f}")
    console = Console()
    console.print(table)
    console.print(f"wrote {escape(str(result.out))} (method {run.solution.method}, {len(run.views)} samples) in "
                  f"{result.elapsed_s:.1f} s; no ground truth here: check it with `bt-grasp perceive --device` on "
                  "known objects")
