"""`bt-grasp detector train --resume`: what it continues is checked before anything is imported or trained (a
folder with no interrupted run, or one started with other options or datasets, is exit 2 and one sentence), and a
resumed run's training time is the sum of its pieces. The resume itself needs the train extra (Ultralytics'
``resume=True``); the shipped model was made with it (its card)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from bt_grasp.cli.main import main
from bt_grasp.detector.train import TrainRequest, _training_seconds, check_resumable, write_data_yaml
from bt_grasp.errors import InputError

from .synthetic_dataset import NAMES, make_synthetic_dataset


def _interrupted_run(tmp_path: Path, epochs: int = 40) -> tuple[Path, Path, Path]:
    train = make_synthetic_dataset(tmp_path / "train", 2, seed=1)
    val = make_synthetic_dataset(tmp_path / "val", 1, seed=2)
    run = tmp_path / "model" / "ultralytics"
    (run / "weights").mkdir(parents=True)
    (run / "weights" / "last.pt").write_bytes(b"weights")
    write_data_yaml(run / "data.yaml", [train], val, NAMES)
    (run / "args.yaml").write_text(yaml.safe_dump({"task": "obb", "epochs": epochs, "imgsz": 64, "seed": 3,
                                                   "batch": 4, "resume": False}))
    return train, val, run


def test_a_matching_run_is_resumed_from_its_last_weights(tmp_path: Path) -> None:
    train, val, run = _interrupted_run(tmp_path)
    request = TrainRequest((train,), val, tmp_path / "model", "m", epochs=40, imgsz=64, seed=3, batch=4,
                           resume=True)
    assert check_resumable(run, request, NAMES) == run / "weights" / "last.pt"
    assert request.command().endswith("--epochs 40 --imgsz 64 --seed 3 --batch 4 --threads 2 --resume")


@pytest.mark.parametrize(("change", "problem"), [
    ({"epochs": 30}, "was started with --epochs 40, not 30"),
    ({"seed": 0}, "was started with --seed 3, not 0"),
    ({"val": None}, "was started on other datasets or classes"),
])
def test_a_run_started_otherwise_is_refused(tmp_path: Path, change: dict[str, object], problem: str) -> None:
    train, val, run = _interrupted_run(tmp_path)
    options: dict[str, object] = {"epochs": 40, "imgsz": 64, "seed": 3, "batch": 4, "val": val, **change}
    request = TrainRequest((train,), options.pop("val"), tmp_path / "model", "m", resume=True,  # type: ignore[arg-type]
                           **options)  # type: ignore[arg-type]
    with pytest.raises(InputError) as caught:
        check_resumable(run, request, NAMES)
    assert problem in str(caught.value)


def test_resume_with_nothing_to_resume_is_one_sentence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    make_synthetic_dataset(tmp_path / "train", 2, seed=1)
    code = main(["detector", "train", str(tmp_path / "train"), "--out", str(tmp_path / "fresh"), "--resume"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "Traceback" not in err
    assert err == (f"bt-grasp: error: --resume: {tmp_path / 'fresh' / 'ultralytics'} holds no interrupted run "
                   "(weights/last.pt, args.yaml and data.yaml)")


def test_training_time_sums_the_pieces_of_a_resumed_run(tmp_path: Path) -> None:
    csv = tmp_path / "results.csv"
    # Ultralytics' time column counts from each start: 3 epochs, killed, resumed for 2 more
    csv.write_text("epoch,time,train/box_loss\n1,100.5,1\n2,201.0,1\n3,300.0,1\n4,110.0,1\n5,220.0,1\n")
    assert _training_seconds(csv) == pytest.approx(520.0)
    csv.write_text("epoch,time\n1,50.0\n2,99.0\n")
    assert _training_seconds(csv) == pytest.approx(99.0)
    assert _training_seconds(tmp_path / "none.csv") is None


def test_weights_must_be_a_checkpoint(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--weights` fine-tunes from an earlier run's checkpoint; an ONNX export (or a missing file) is refused in one
    sentence before anything is imported."""
    make_synthetic_dataset(tmp_path / "train", 2, seed=1)
    onnx = tmp_path / "model.onnx"
    onnx.write_bytes(b"not trainable")
    code = main(["detector", "train", str(tmp_path / "train"), "--out", str(tmp_path / "out"), "--weights", str(onnx)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err == (f"bt-grasp: error: --weights: {onnx} is not an Ultralytics checkpoint (.pt) here: "
                                 "give an earlier run's OUT/ultralytics/weights/best.pt (an ONNX export cannot be "
                                 "trained)")
    request = TrainRequest((tmp_path / "train",), None, tmp_path / "out", "m", weights=tmp_path / "best.pt")
    assert request.command().endswith("--threads 2 --weights " + str(tmp_path / "best.pt"))
