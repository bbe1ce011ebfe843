"""`bt-grasp detector`: the learned oriented-box detector's tools (docs/detector.md).

`check MODEL` opens a YOLO-OBB ONNX export as the pipeline would and says what it is (or, in one sentence, why it
cannot be used); `dataset` renders labelled pictures of bt_grasp's scenes in the Ultralytics OBB format; `train`
trains a YOLO11n-OBB from scratch with the `train` extra (Ultralytics, AGPL-3.0) and writes the ONNX export and its
model card; `eval` scores a model on a dataset through bt_grasp's own inference path.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer

detector_app = typer.Typer(help="The learned oriented-box detector: check a model, make a dataset, train, evaluate.",
                           no_args_is_help=True)


@detector_app.command("check")
def check(
    model: Path = typer.Argument(..., help="A YOLO-OBB ONNX export (Ultralytics `format=onnx`)."),
    imgsz: int | None = typer.Option(None, "--imgsz", help="The input size you expect the model to take."),
    class_names: list[str] = typer.Option([], "--class", help="A class the model must have (repeatable)."),
) -> None:
    """Open MODEL with onnxruntime, check it is a YOLO-OBB export and print its input size and classes."""
    from bt_grasp.detector.model import ObbModel
    from bt_grasp.files.terminal_text import shown

    loaded = ObbModel.load(model, imgsz=imgsz)
    for name in class_names:
        loaded.class_id(name, source="--class")
    info = loaded.info
    anchors = "dynamic" if info.anchors is None else str(info.anchors)
    # the class names are the model file's text: shown, never obeyed (a name can hold terminal escapes)
    typer.echo(shown(f"{model}: YOLO-OBB, input {info.input_hw[0]}x{info.input_hw[1]}, {anchors} anchors, "
                     f"{len(info.names)} classes ({', '.join(info.names)})", newlines=False))


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


@detector_app.command("train")
def train(
    datasets: list[Path] = typer.Argument(..., help="Dataset folders made by `bt-grasp detector dataset` (joined)."),
    out: Path = typer.Option(..., "--out", help="Folder for NAME.onnx, MODEL_CARD.md/.json and the run's files."),
    val: Path | None = typer.Option(None, "--val", help="A held-out dataset folder (other seeds): validation and "
                                                        "the card's figures. Without it: the training images."),
    name: str = typer.Option("model", "--name", help="The ONNX file's name: OUT/NAME.onnx."),
    epochs: int = typer.Option(30, "--epochs", min=1, help="Training epochs."),
    imgsz: int = typer.Option(320, "--imgsz", min=32, help="Input size (pixels, a multiple of 32)."),
    seed: int = typer.Option(0, "--seed", help="Ultralytics' seed (deterministic=True, workers=0)."),
    batch: int = typer.Option(16, "--batch", min=1, help="Batch size."),
    threads: int = typer.Option(2, "--threads", min=1, help="torch threads."),
    resume: bool = typer.Option(False, "--resume", help="Continue the interrupted run in --out from its last "
                                                         "finished epoch (the same datasets and options)."),
    weights: Path | None = typer.Option(None, "--weights", help="Start from an earlier run's weights "
                                                               "(OUT/ultralytics/weights/best.pt): fine-tuning."),
) -> None:
    """Train a YOLO11n-OBB from scratch on CPU (needs the `train` extra: Ultralytics, AGPL-3.0, and torch), export it
    to ONNX and write its model card with the held-out figures measured as `detector eval` measures them."""
    from bt_grasp.detector.card import ModelCard, machine, sha256
    from bt_grasp.detector.evaluate import dataset_images, evaluate_model, format_report
    from bt_grasp.detector.train import ARCHITECTURE, TrainRequest, dataset_command, train_model
    from bt_grasp.errors import InputError

    if imgsz % 32:
        raise InputError("--imgsz", f"must be a multiple of 32 (the network's stride), got {imgsz}")
    if not name or "/" in name or name.startswith("."):
        raise InputError("--name", f"must be a plain file name, got '{name}'")
    from bt_grasp.files.output_files import check_output_file, check_output_folder

    check_output_folder(out, "--out")  # before training: where its files go can be written
    check_output_file(out / f"{name}.onnx", "--out", example="model.onnx")
    request = TrainRequest(tuple(datasets), val, out, name, epochs, imgsz, seed, batch, threads, resume, weights)
    result = train_model(request)
    held_out = evaluate_model(result.onnx, val) if val is not None else None
    folders = [(d, "train") for d in datasets] + ([(val, "val")] if val is not None else [])
    card = ModelCard(
        model_file=result.onnx.name, sha256=sha256(result.onnx),
        architecture=f"YOLO11n-OBB (Ultralytics {ARCHITECTURE}, "
                     + ("from scratch)" if weights is None else f"fine-tuned from {weights})"),
        classes=result.names, imgsz=imgsz,
        datasets=tuple({"folder": str(d), "role": role, "images": len(dataset_images(d)),
                        "command": dataset_command(d)} for d, role in folders),
        train_command=request.command(),
        eval_command=f"bt-grasp detector eval {out / (name + '.onnx')} {val}" if val is not None else "",
        epochs=result.epochs_run or epochs, seed=seed, training_seconds=result.seconds, held_out=held_out,
        ultralytics_metrics=result.ultralytics_metrics, versions=result.versions, machine=machine())
    md, js = card.write(out)
    typer.echo(f"{result.onnx}: trained {result.epochs_run} epochs in {result.seconds / 60:.1f} min; card {md}, {js}")
    if held_out is not None:
        from bt_grasp.files.terminal_text import shown

        typer.echo(shown(format_report(held_out)))


@detector_app.command("eval")
def evaluate(
    model: Path = typer.Argument(..., help="A YOLO-OBB ONNX export."),
    dataset: Path = typer.Argument(..., help="A dataset folder (images/, labels/, data.yaml) with the model's "
                                             "classes."),
    as_json: bool = typer.Option(False, "--json", help="Print the report as one JSON object."),
) -> None:
    """mAP50, mAP50-95, the median angle error of elongated objects, per class, and the confusion between classes,
    measured through bt_grasp's own inference path (onnxruntime, its decoder and rotated NMS)."""
    from bt_grasp.detector.evaluate import evaluate_model, format_report
    from bt_grasp.files.terminal_text import shown

    report = evaluate_model(model, dataset)
    if as_json:  # JSON escapes control characters itself
        typer.echo(json.dumps({"model": str(model), "dataset": str(dataset), **report.to_json()}))
    else:  # the class names are the model's and the dataset's text: shown, never obeyed
        typer.echo(shown(format_report(report)))


def register(app: typer.Typer) -> None:
    app.add_typer(detector_app, name="detector")
