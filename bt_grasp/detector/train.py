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

    def command(self) -> str:
        """The command line that makes this model."""
        parts = ["bt-grasp detector train", *(str(d) for d in self.datasets)]
        if self.val is not None:
            parts += ["--val", str(self.val)]
        parts += ["--out", str(self.out), "--name", self.name, "--epochs", str(self.epochs), "--imgsz",
                  str(self.imgsz), "--seed", str(self.seed), "--batch", str(self.batch), "--threads",
                  str(self.threads)]
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
    from bt_grasp.config import read_yaml

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
    from importlib.util import find_spec

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
    from importlib.metadata import PackageNotFoundError, version

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


def train_model(request: TrainRequest) -> TrainResult:
    """Train, export to ``out/NAME.onnx`` (opset 18, simplified with onnxslim, fixed input size) and return what
    happened. Ultralytics prints its own progress."""
    names = check_datasets(request.datasets, request.val)
    require_training_extra()
    out = request.out.resolve()  # Ultralytics puts a relative project under its own runs folder
    run_dir = out / RUN_FOLDER
    _offline_config(run_dir / "config")  # before Ultralytics is first imported: it reads the settings then
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # before torch's OpenMP starts: no spinning at barriers
    import torch
    import ultralytics.utils.torch_utils as torch_utils
    from ultralytics import YOLO

    torch.set_num_threads(request.threads)
    # Ultralytics resets torch's threads to its NUM_THREADS (cores - 1: one on a 2-core machine) when it picks the
    # CPU; the number asked for wins
    torch_utils.NUM_THREADS = request.threads  # type: ignore[attr-defined]
    data = write_data_yaml(run_dir / "data.yaml", request.datasets, request.val, names)
    model = YOLO(ARCHITECTURE, task="obb")
    start = time.perf_counter()
    model.train(data=str(data), epochs=request.epochs, imgsz=request.imgsz, batch=request.batch, device="cpu",
                workers=0, seed=request.seed, deterministic=True, pretrained=False, project=str(out),
                name=RUN_FOLDER, exist_ok=True, plots=False, amp=False, patience=request.epochs, verbose=True,
                val=False)  # validated once, after the last epoch: a young model's validation costs a third of an epoch
    seconds = time.perf_counter() - start
    best = run_dir / "weights" / "best.pt"
    if not best.is_file():
        best = run_dir / "weights" / "last.pt"
    exported = Path(str(YOLO(str(best), task="obb").export(format="onnx", imgsz=request.imgsz, opset=ONNX_OPSET,
                                                             simplify=True, dynamic=False, device="cpu")))
    from bt_grasp.output_files import copy_output_file

    onnx_path = copy_output_file(exported, out / f"{request.name}.onnx", "--out", example="model.onnx")
    epochs_run, metrics = _last_row(run_dir / "results.csv")
    return TrainResult(onnx_path, best, seconds, epochs_run, metrics, versions(), names)
