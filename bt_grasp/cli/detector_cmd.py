"""`bt-grasp detector`: the learned oriented-box detector's tools (docs/detector.md).

`check MODEL` opens a YOLO-OBB ONNX export as the pipeline would and says what it is (or, in one sentence, why it
cannot be used); `dataset` renders labelled pictures of bt_grasp's scenes in the Ultralytics OBB format.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

detector_app = typer.Typer(help="The learned oriented-box detector: check a model, make a dataset.",
                           no_args_is_help=True)


@detector_app.command("check")
def check(
    model: Path = typer.Argument(..., help="A YOLO-OBB ONNX export (Ultralytics `format=onnx`)."),
    imgsz: int | None = typer.Option(None, "--imgsz", help="The input size you expect the model to take."),
    class_names: list[str] = typer.Option([], "--class", help="A class the model must have (repeatable)."),
) -> None:
    """Open MODEL with onnxruntime, check it is a YOLO-OBB export and print its input size and classes."""
    from bt_grasp.detector.model import ObbModel

    loaded = ObbModel.load(model, imgsz=imgsz)
    for name in class_names:
        loaded.class_id(name, source="--class")
    info = loaded.info
    anchors = "dynamic" if info.anchors is None else str(info.anchors)
    typer.echo(f"{model}: YOLO-OBB, input {info.input_hw[0]}x{info.input_hw[1]}, {anchors} anchors, "
               f"{len(info.names)} classes ({', '.join(info.names)})")


@detector_app.command("dataset")
def dataset(
    scenes: list[Path] = typer.Option(..., "--scenes", help="Scene files, taken in turn: --scenes A B C."),
    more_scenes: list[Path] = typer.Argument(None, hidden=True, help="The scene files after the first."),
    images: int = typer.Option(..., "--images", min=1, help="How many pictures to render."),
    out: Path = typer.Option(..., "--out", help="Folder to write images/, labels/, data.yaml, preview.png."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random draw; the same seed writes the same bytes."),
    mount: str = typer.Option("scene", "--mount", help="scene (each scene's mount), eye-to-hand, eye-in-hand "
                                                      "or both (alternating)."),
    min_pixels: int = typer.Option(60, "--min-pixels", min=1, help="Objects with fewer visible pixels get no "
                                                                    "label."),
) -> None:
    """Render labelled pictures of bt_grasp's scenes for training a YOLO-OBB model (Ultralytics OBB format)."""
    from bt_grasp.sim.labelling import make_dataset

    t0 = time.perf_counter()
    summary = make_dataset([*scenes, *(more_scenes or [])], images, out, seed, mount=mount, min_pixels=min_pixels)
    counts = ", ".join(f"{name} {n}" for name, n in summary.per_class.items()) or "none"
    typer.echo(f"{out}: {summary.images} pictures, {summary.labels} labels ({counts}) in "
               f"{time.perf_counter() - t0:.0f} s; preview {out / 'preview.png'}")


def register(app: typer.Typer) -> None:
    app.add_typer(detector_app, name="detector")
