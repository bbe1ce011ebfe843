"""`bt-grasp calibrate`: hand-eye calibration in the simulator, written to a calibration YAML file.

It runs the ``Calibrate`` leaf's own procedure (``bt_grasp.episode.calibration.calibrate_in_sim``) on a
simulated cell with a ChArUco board (on the gripper for eye-to-hand, on the table for eye-in-hand) and,
because this is a simulator, judges the result against the true camera pose (printed as such; never used
to produce the calibration).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from bt_grasp.cli.text_width import wrap
from bt_grasp.interfaces import Mount

if TYPE_CHECKING:  # annotations only
    pass

MOUNTS = tuple(m.value for m in Mount)


def calibrate(
    scene: Path = typer.Option(Path("scenes/tabletop.yaml"), "--scene", help="Scene YAML file."),
    mount: Mount = typer.Option(Mount.EYE_TO_HAND, "--mount", help="Where the camera is."),
    out: Path | None = typer.Option(None, "--out", help="Calibration YAML file to write (with --cell: the file the "
                                    "cell file names)."),
    cell: Path | None = typer.Option(None, "--cell", help="Calibrate a real cell's camera (or a twin's) instead: "
                                     "the arm moves the board on its gripper through the views (docs/real-cell.md)."),
    yes: bool = typer.Option(False, "--yes", help="With --cell: do not ask before the arm's first motion."),
    seed: int = typer.Option(0, "--seed", help="Seed of the world (camera noise) and of the view planner."),
    poses: int = typer.Option(20, "--poses", min=4, max=60, help="Number of board views to collect."),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object."),
) -> None:
    """Hand-eye calibrate the simulated camera (or a real cell's: --cell) with a ChArUco board and write the
    calibration file."""
    if cell is not None:
        from bt_grasp.cli.cell_calibrate_options import calibrate_on_cell

        calibrate_on_cell(cell, out, poses, seed, yes, as_json)
        return
    if out is None:
        from bt_grasp.errors import InputError

        raise InputError("--out", "name the calibration file to write (--out calib.yaml)")
    from bt_grasp.episode.calibration import calibrate_in_sim
    from bt_grasp.errors import InputError
    from bt_grasp.perception.calibration_file import save_calibration
    from bt_grasp.scene.format import load_scene

    if mount not in MOUNTS:
        raise InputError("--mount", f"expected eye-to-hand or eye-in-hand, got '{mount}'")
    load_scene(scene)  # a bad scene file fails here with file:line, before the simulator starts
    from bt_grasp.files.output_files import check_output_file

    check_output_file(out, "--out", example="calibration.yaml", inputs=(scene,))  # and a place it cannot write to
    from rich.console import Console

    progress_console = Console(stderr=True)  # progress on stderr, and only on a terminal: a pipe gets none
    if as_json or not progress_console.is_terminal:
        result = calibrate_in_sim(scene, mount, seed, poses)
    else:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

        with Progress(TextColumn("calibrating {task.fields[mount]}"), BarColumn(), MofNCompleteColumn(),
                      TextColumn("{task.fields[note]}"), console=progress_console, transient=True) as bar:
            task = bar.add_task("views", total=poses, mount=mount, note="building the world")

            def progress(done: int, total: int, note: str) -> None:
                bar.update(task, completed=min(done, poses), total=max(total, poses), note=note)

            result = calibrate_in_sim(scene, mount, seed, poses, progress)
    run = result.run
    save_calibration(run.calibration, out)
    chosen = run.solution.chosen
    true_mm, true_deg = result.true_error_per_method[run.solution.method]
    summary = {
        "mount": mount,
        "out": str(out),
        "method": run.solution.method,
        "samples": len(run.views),
        "visited": run.visited,
        "rejected": run.rejected,
        "residual_mm": round(chosen.residual_mm, 4),
        "residual_deg": round(chosen.residual_deg, 5),
        "reprojection_px": round(chosen.reprojection_px, 4),
        "true_error_mm": round(true_mm, 4),
        "true_error_deg": round(true_deg, 5),
        "per_method": {
            name: {**r.as_dict(), "true_error_mm": round(result.true_error_per_method[name][0], 4),
                   "true_error_deg": round(result.true_error_per_method[name][1], 5)}
            for name, r in run.solution.per_method.items()
        },
        "elapsed_s": round(result.elapsed_s, 2),
    }
    if as_json:
        typer.echo(json.dumps(summary))
        return
    rows: list[tuple[str, bool, tuple[str, ...]]] = []
    for name, r in run.solution.per_method.items():
        mm, deg = result.true_error_per_method[name]
        rows.append((name, name == run.solution.method, (f"{r.scatter_mm:.3f}", f"{r.residual_mm:.3f}",
                                                         f"{r.residual_deg:.4f}", f"{r.reprojection_px:.3f}",
                                                         f"{mm:.3f}", f"{deg:.4f}")))
    typer.echo(calibration_table(f"hand-eye calibration ({mount}): {len(run.views)} views of {run.visited} visited",
                                 rows))
    typer.echo(wrap(f"wrote {out} (method {run.solution.method}, {len(run.views)} samples) in "
                    f"{result.elapsed_s:.1f} s"))


#: the table's columns after the method's: two header lines each (every value is at most 7 characters)
COLUMNS = (("scatter", "mm"), ("residual", "mm"), ("residual", "deg"), ("reproj", "px"), ("true err", "mm*"),
           ("true err", "deg*"))


def calibration_table(title: str, rows: list[tuple[str, bool, tuple[str, ...]]]) -> str:
    """The per-method table as plain text within 80 columns, every header and value whole (it was a Rich table
    that cut both at 80 columns and in a pipe): the chosen method marked ``>``, the ground-truth columns ``*``."""
    name_width = max([len("method")] + [len(name) for name, _, _ in rows])
    widths = [max(len(a), len(b), *(len(values[i]) for _, _, values in rows)) for i, (a, b) in enumerate(COLUMNS)]

    def line(mark: str, name: str, cells: tuple[str, ...]) -> str:
        return (f"{mark} {name:<{name_width}}" + "".join(f"  {c:>{w}}" for c, w in zip(cells, widths, strict=True))
                ).rstrip()

    lines = [wrap(title), line(" ", "method", tuple(a for a, _ in COLUMNS)),
             line(" ", "", tuple(b for _, b in COLUMNS))]
    lines += [line(">" if chosen else " ", name, values) for name, chosen, values in rows]
    lines.append(wrap("> the method chosen; * simulator ground truth (judge only): the error against the true "
                      "camera pose, which the calibration never reads."))
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    app.command("calibrate")(calibrate)
