"""`bt-grasp detector train`: a YOLO11n-OBB trained from scratch with Ultralytics on CPU, exported to ONNX.

Ultralytics (AGPL-3.0) and torch come from the ``train`` extra (``pip install 'bt-grasp[train]'``) and are imported
only here, inside ``train_model``: the runtime never imports them (a test checks bt_grasp imports without them).
Weights trained with Ultralytics fall under its AGPL-3.0 licence; the model card says so.

Offline and reproducible where Ultralytics allows: the model is built from its YAML (``pretrained=False``: no
weights are downloaded), ``YOLO_OFFLINE=1``, a config folder of its own inside the output (nothing written to the
home folder) holding a copy of a local TrueType font as ``Arial.ttf`` (Ultralytics otherwise tries to download
it), ``workers=0``, ``deterministic=True``, ``seed``, torch on ``threads`` threads. Validation runs once, after
the last epoch (so ``best.pt`` is the last epoch's weights).

torch's OpenMP threads wait for each other *passively* (``OMP_WAIT_POLICY=PASSIVE`` unless the environment says
otherwise): GNU OpenMP's default spins at every barrier, and on a shared machine a thread spinning for one that
was descheduled burns its whole time slice. Measured on this 2-core machine at load average 14 (800 pictures,
320 px, batch 16): one thread 9.7-10.9 s per batch (1.5 s of processor time), two passive threads 5.3-5.4 s
(1.75 s of processor time).
"""

from __future__ import annotations

import csv
import os
import platform
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml

from bt_grasp.detector.evaluate import DatasetError, dataset_images, dataset_names
from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.bounded_yaml import load_value
from bt_grasp.files.config import read_yaml
from bt_grasp.files.output_files import copy_output_file

#: the network: Ultralytics' YOLO11 OBB family at the "n" scale, built from its YAML
ARCHITECTURE = "yolo11n-obb.yaml"
ONNX_OPSET = 18
RUN_FOLDER = "ultralytics"  # MODEL_DIR/ultralytics: the run (weights/best.pt, results.csv, args.yaml, config)


class TrainingExtraMissing(InputError):
    """The ``train`` extra (ultralytics, torch) is not installed."""


@dataclass(frozen=True)
class TrainRequest:
    """What to train: dataset folders (made by `bt-grasp detector dataset`), held-out validation folder (none:
    validate on the training images), the output folder and file name, epochs, input size, seed, batch, threads."""

    datasets: tuple[Path, ...]
    val: Path | None
    out: Path
    name: str = "model"
    epochs: int = 30
    imgsz: int = 320
    seed: int = 0
    batch: int = 16
    threads: int = 2
    #: continue the interrupted run in ``out`` from its last finished epoch (Ultralytics' resume): the same
    #: datasets, epochs and settings as when it started
    resume: bool = False
    #: start from these weights (an earlier run's ``ultralytics/weights/best.pt``: fine-tuning), not from scratch
    weights: Path | None = None

    def command(self) -> str:
        """The command line that makes this model."""
        parts = ["bt-grasp detector train", *(str(d) for d in self.datasets)]
        if self.val is not None:
            parts += ["--val", str(self.val)]
        parts += ["--out", str(self.out), "--name", self.name, "--epochs", str(self.epochs), "--imgsz",
                  str(self.imgsz), "--seed", str(self.seed), "--batch", str(self.batch), "--threads",
                  str(self.threads)]
        if self.weights is not None:
            parts += ["--weights", str(self.weights)]
        if self.resume:
            parts.append("--resume")
        return " ".join(parts)


@dataclass(frozen=True)
class TrainResult:
    onnx: Path
    best_pt: Path
    seconds: float
    epochs_run: int
    ultralytics_metrics: dict[str, float]  # the last epoch's row of results.csv (its own validation)
    versions: dict[str, str]
    names: tuple[str, ...]


def check_datasets(datasets: Sequence[Path], val: Path | None) -> tuple[str, ...]:
    """Every folder is a dataset with images and the same class names; returns the names."""
    if not datasets:
        raise DatasetError("DATASET", "give at least one dataset folder")
    names = dataset_names(datasets[0])
    for folder in [*datasets, *([val] if val is not None else [])]:
        theirs = dataset_names(folder)
        if theirs != names:
            raise DatasetError(folder / "data.yaml", f"its classes ({', '.join(theirs)}) differ from "
                                                     f"{datasets[0] / 'data.yaml'}'s ({', '.join(names)})", "names")
        dataset_images(folder)
        if not (folder / "labels").is_dir():
            raise DatasetError(folder, "has no labels/ folder")
    return names


def dataset_command(folder: Path) -> str | None:
    """The `bt-grasp detector dataset` command that made ``folder``, from its manifest (None without one)."""
    manifest = folder / "manifest.yaml"
    if not manifest.is_file():
        return None

    try:
        doc, _ = read_yaml(manifest)  # bounded: size, nesting, aliases
    except InputError:
        return None
    keys = ("scenes", "images", "seed", "mount", "min_pixels")
    if not isinstance(doc, dict) or doc.get("made_by") != "bt-grasp detector dataset":
        return None
    if not all(k in doc for k in keys) or not isinstance(doc["scenes"], list):
        return None
    return (f"bt-grasp detector dataset --scenes {' '.join(str(s) for s in doc['scenes'])} --images {doc['images']} "
            f"--out {folder} --seed {doc['seed']} --mount {doc['mount']} --min-pixels {doc['min_pixels']}")


def require_training_extra() -> None:
    """The training extra is installed (found without importing it), or a one-sentence error says how to get it."""
    from importlib.util import find_spec  # deferred: start-up time (only when training checks its extra)

    for package in ("torch", "torchvision", "ultralytics", "onnxslim"):
        try:
            found = find_spec(package) is not None
        except ImportError:
            found = False
        if not found:
            raise TrainingExtraMissing(
                "bt-grasp detector train", f"needs the training extra ({package} is not installed): "
                                           "pip install 'bt-grasp[train]' (ultralytics, AGPL-3.0, and torch)")


def _offline_config(config_dir: Path) -> None:
    """Ultralytics' settings in a folder of our own, offline, with a local font standing in for Arial.ttf."""
    config_dir.mkdir(parents=True, exist_ok=True)
    os.environ["YOLO_CONFIG_DIR"] = str(config_dir)
    os.environ["YOLO_OFFLINE"] = "1"
    import matplotlib

    font = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    target = config_dir / "Ultralytics"
    target.mkdir(exist_ok=True)
    for name in ("Arial.ttf", "Arial.Unicode.ttf"):
        if not (target / name).exists():
            shutil.copyfile(font, target / name)


def write_data_yaml(path: Path, datasets: Sequence[Path], val: Path | None, names: Sequence[str]) -> Path:
    """Ultralytics' dataset file joining the folders: absolute image folders, the held-out ones for validation."""
    doc = {"path": str(path.parent.resolve()),
           "train": [str((d / "images").resolve()) for d in datasets],
           "val": [str((d / "images").resolve()) for d in ([val] if val is not None else datasets)],
           "names": dict(enumerate(names))}
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def versions() -> dict[str, str]:
    from importlib.metadata import PackageNotFoundError, version  # deferred: as above

    out = {"python": platform.python_version()}
    for package in ("bt-grasp", "ultralytics", "torch", "torchvision", "onnx", "onnxslim", "onnxruntime"):
        try:
            out[package] = version(package)
        except PackageNotFoundError:
            continue
    return out


def _last_row(results_csv: Path) -> tuple[int, dict[str, float]]:
    if not results_csv.is_file():
        return 0, {}
    with results_csv.open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        return 0, {}
    last = {k.strip(): float(v) for k, v in rows[-1].items() if k and v not in (None, "")}
    return len(rows), {k: v for k, v in last.items() if k.startswith("metrics/")}


def _training_seconds(results_csv: Path) -> float | None:
    """The run's training time from Ultralytics' ``time`` column: it counts from each start, so a run resumed
    after an interruption is the sum of its pieces (the time lost with the interrupted epoch is not counted)."""
    if not results_csv.is_file():
        return None
    with results_csv.open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    total, previous = 0.0, 0.0
    for row in rows:
        value = next((v for k, v in row.items() if k and k.strip() == "time"), None)
        try:
            now = float(value) if value not in (None, "") else previous
        except ValueError:
            return None
        if now < previous:  # a resumed piece starts again from zero
            total += previous
        previous = now
    return total + previous if rows else None


def check_resumable(run_dir: Path, request: TrainRequest, names: Sequence[str]) -> Path:
    """The interrupted run's ``weights/last.pt`` when ``run_dir`` holds one that ``request`` continues: the same
    datasets, classes, epochs, input size, seed and batch as it was started with (read from its ``args.yaml`` and
    ``data.yaml``); otherwise an InputError naming what differs. Before torch is imported."""
    last = run_dir / "weights" / "last.pt"
    args_file, data_file = run_dir / "args.yaml", run_dir / "data.yaml"
    if not last.is_file() or not args_file.is_file() or not data_file.is_file():
        raise InputError("--resume", f"{run_dir} holds no interrupted run (weights/last.pt, args.yaml and data.yaml)")

    docs = []
    for path in (args_file, data_file):
        try:
            doc = load_value(read_user_file(path).decode("utf-8", errors="replace"))
        except ValueError as exc:
            raise InputError(str(path), str(exc)) from None
        if not isinstance(doc, dict):
            raise InputError(str(path), "is not a mapping (the interrupted run's own file)")
        docs.append(doc)
    args, data = docs
    started = {"epochs": args.get("epochs"), "imgsz": args.get("imgsz"), "seed": args.get("seed"),
               "batch": args.get("batch")}
    asked = {"epochs": request.epochs, "imgsz": request.imgsz, "seed": request.seed, "batch": request.batch}
    for key, value in asked.items():
        if started[key] != value:
            raise InputError("--resume", f"the run in {run_dir} was started with --{key} {started[key]}, not {value}")
    train = [str(Path(d).resolve() / "images") for d in request.datasets]
    val = [str(Path(request.val).resolve() / "images")] if request.val is not None else train
    recorded = (list(data.get("train") or []), list(data.get("val") or []))
    if recorded != (train, val) or list((data.get("names") or {}).values()) != list(names):
        raise InputError("--resume", f"the run in {run_dir} was started on other datasets or classes "
                                     f"({data_file}); give the same folders and --val")
    return last


def train_model(request: TrainRequest) -> TrainResult:
    """Train, export to ``out/NAME.onnx`` (opset 18, simplified with onnxslim, fixed input size) and return what
    happened. Ultralytics prints its own progress."""
    names = check_datasets(request.datasets, request.val)
    out = request.out.resolve()  # Ultralytics puts a relative project under its own runs folder
    run_dir = out / RUN_FOLDER
    last = check_resumable(run_dir, request, names) if request.resume else None
    if request.weights is not None and (request.weights.suffix != ".pt" or not request.weights.is_file()):
        raise InputError("--weights", f"{request.weights} is not an Ultralytics checkpoint (.pt) here: give "
                                      "an earlier run's OUT/ultralytics/weights/best.pt (an ONNX export cannot be "
                                      "trained)")
    require_training_extra()
    _offline_config(run_dir / "config")  # before Ultralytics is first imported: it reads the settings then
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # before torch's OpenMP starts: no spinning at barriers
    import torch
    import ultralytics.utils.torch_utils as torch_utils
    from ultralytics import YOLO

    torch.set_num_threads(request.threads)
    # Ultralytics resets torch's threads to its NUM_THREADS (cores - 1: one on a 2-core machine) when it picks the
    # CPU; the number asked for wins
    torch_utils.NUM_THREADS = request.threads  # type: ignore[attr-defined]
    start = time.perf_counter()
    if last is not None:
        YOLO(str(last), task="obb").train(resume=True)  # the saved run's own arguments, from its next epoch
    else:
        data = write_data_yaml(run_dir / "data.yaml", request.datasets, request.val, names)
        # fine-tuning: Ultralytics loads a checkpoint's weights into the model built from the architecture when
        # `pretrained` names it (with pretrained=False even a model loaded from a .pt starts from random weights)
        initial: bool | str = False if request.weights is None else str(request.weights.resolve())
        model = YOLO(ARCHITECTURE, task="obb")
        model.train(data=str(data), epochs=request.epochs, imgsz=request.imgsz, batch=request.batch, device="cpu",
                    workers=0, seed=request.seed, deterministic=True, pretrained=initial, project=str(out),
                    name=RUN_FOLDER, exist_ok=True, plots=False, amp=False, patience=request.epochs, verbose=True,
                    val=False)  # validated once, after the last epoch: a young model's validation costs a third
    seconds = time.perf_counter() - start
    best = run_dir / "weights" / "best.pt"
    if not best.is_file():
        best = run_dir / "weights" / "last.pt"
    exported = Path(str(YOLO(str(best), task="obb").export(format="onnx", imgsz=request.imgsz, opset=ONNX_OPSET,
                                                             simplify=True, dynamic=False, device="cpu")))

    onnx_path = copy_output_file(exported, out / f"{request.name}.onnx", "--out", example="model.onnx")
    epochs_run, metrics = _last_row(run_dir / "results.csv")
    if request.resume:  # the whole run's time, not only this command's
        seconds = _training_seconds(run_dir / "results.csv") or seconds
    return TrainResult(onnx_path, best, seconds, epochs_run, metrics, versions(), names)
