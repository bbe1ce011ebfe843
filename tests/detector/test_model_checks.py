"""A model that is not a YOLO-OBB export, a class it does not have, an input size it does not take: one sentence
each (exit 2 at the command line), never a traceback."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.cli.main import main
from bt_grasp.detector.model import ModelError, ObbModel, card_path

from .tiny_onnx import raw_output, write_model

NAMES = {0: "mug", 1: "banana", 2: "screwdriver"}
GOOD = raw_output([(100.0, 115.0, 60.0, 20.0, 0.375, 1, 0.875)], nc=3)


def _one_sentence(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "error: " in err and "\n" not in err and "Traceback" not in err
    return err


@pytest.mark.parametrize(
    ("output", "shape", "message"),
    [
        (np.zeros((8, 16), np.float32), None, r"its output has rank 2 \(\[8, 16\]\), expected \[1, 8, anchors\]"),
        (np.zeros((1, 16, 8), np.float32), None, r"is anchors-first; expected channels first \[1, 8, anchors\]"),
        (np.zeros((1, 7, 16), np.float32), None, r"has no angle channel: a detection \(not OBB\) export"),
        (np.zeros((1, 12, 16), np.float32), None, r"does not fit 3 classes"),
    ],
    ids=["rank-2", "anchors-first", "detect-export", "wrong-classes"],
)
def test_a_file_that_is_not_an_obb_export_is_refused(tmp_path: Path, output, shape, message) -> None:
    path = write_model(tmp_path / "m.onnx", output, names=NAMES, output_shape=shape)
    with pytest.raises(ModelError, match=message) as info:
        ObbModel.load(path)
    assert str(info.value).startswith(f"{path}: is not a YOLO-OBB export")


def test_two_outputs_are_refused(tmp_path: Path) -> None:
    path = write_model(tmp_path / "m.onnx", GOOD, names=NAMES, outputs=2)
    with pytest.raises(ModelError, match="it has 2 outputs, expected one"):
        ObbModel.load(path)


def test_a_file_that_is_not_onnx_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "notes.onnx"
    path.write_text("this is not a model\n")
    with pytest.raises(ModelError, match=r"notes.onnx: is not an ONNX model onnxruntime can open"):
        ObbModel.load(path)
    with pytest.raises(ModelError, match="no such model file"):
        ObbModel.load(tmp_path / "absent.onnx")


def test_class_names_from_metadata_or_the_card(tmp_path: Path) -> None:
    no_names = write_model(tmp_path / "plain.onnx", GOOD)
    with pytest.raises(ModelError, match=r"has no class names: neither 'names' in its ONNX metadata nor a card "
                                         r"plain.card.yaml"):
        ObbModel.load(no_names)
    card_path(no_names).write_text("names: [cup, fork, spoon]\nimgsz: 320\n")
    assert ObbModel.load(no_names).names == ("cup", "fork", "spoon")
    card_path(no_names).write_text("names: {0: cup, 2: spoon}\n")
    with pytest.raises(ModelError, match=r"plain.card.yaml: class names must be non-empty strings indexed 0, 1, 2"):
        ObbModel.load(no_names)
    # the export's own metadata wins over a card
    tagged = write_model(tmp_path / "tagged.onnx", GOOD, names=NAMES)
    card_path(tagged).write_text("names: [cup, fork, spoon]\n")
    assert ObbModel.load(tagged).names == ("mug", "banana", "screwdriver")


def test_unknown_class_says_did_you_mean(tmp_path: Path) -> None:
    model = ObbModel.load(write_model(tmp_path / "m.onnx", GOOD, names=NAMES))
    with pytest.raises(ModelError, match=r"class: the model m.onnx has no class 'bananna'; did you mean 'banana'\? "
                                         r"\(its classes: mug, banana, screwdriver\)"):
        model.class_id("bananna")
    assert model.class_id("screwdriver") == 2


def test_input_size_mismatch(tmp_path: Path) -> None:
    path = write_model(tmp_path / "m.onnx", GOOD, names=NAMES)
    with pytest.raises(ModelError, match=r"takes 320x320 images, not the 640x640 asked for"):
        ObbModel.load(path, imgsz=640)
    lying = write_model(tmp_path / "lying.onnx", GOOD, names=NAMES, imgsz=[640, 640])
    with pytest.raises(ModelError, match=r"says its input is 640x640 but its graph takes 320x320"):
        ObbModel.load(lying)
    dynamic = write_model(tmp_path / "dyn.onnx", GOOD, names=NAMES, input_shape=(1, 3, "height", "width"))
    with pytest.raises(ModelError, match=r"has a dynamic input size and no 'imgsz'"):
        ObbModel.load(dynamic)
    sized = write_model(tmp_path / "sized.onnx", GOOD, names=NAMES, input_shape=(1, 3, "height", "width"),
                        imgsz=[256, 320])
    assert ObbModel.load(sized).info.input_hw == (256, 320)


def test_cli_check_prints_the_model_and_exits_2_on_each_problem(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = write_model(tmp_path / "good.onnx", GOOD, names=NAMES)
    assert main(["detector", "check", str(good)]) == 0
    out = capsys.readouterr().out
    assert "3 classes (mug, banana, screwdriver)" in out and "input 320x320" in out
    assert main(["detector", "check", str(good), "--class", "mugg"]) == 2
    assert "did you mean 'mug'?" in _one_sentence(capsys)
    assert main(["detector", "check", str(good), "--imgsz", "640"]) == 2
    assert "takes 320x320 images, not the 640x640" in _one_sentence(capsys)
    bad = write_model(tmp_path / "bad.onnx", np.zeros((1, 16, 8), np.float32), names=NAMES)
    assert main(["detector", "check", str(bad)]) == 2
    assert "is not a YOLO-OBB export" in _one_sentence(capsys)


def test_onnxruntime_is_imported_only_when_a_model_is_loaded(tmp_path: Path) -> None:
    import json
    import subprocess
    import sys

    path = write_model(tmp_path / "m.onnx", GOOD, names=NAMES)
    probe = (
        "import json, sys\n"
        "import bt_grasp.detector.model, bt_grasp.detector.obb, bt_grasp.detector.letterbox\n"
        "before = 'onnxruntime' in sys.modules\n"
        f"bt_grasp.detector.model.ObbModel.load({str(path)!r})\n"
        "print(json.dumps([before, 'onnxruntime' in sys.modules]))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [False, True]


@pytest.mark.parametrize(("imgsz", "input_shape", "message"), [
    ("abc", (1, 3, "h", "w"), r"imgsz must be a positive size or \[height, width\], got 'abc'"),
    ("[" * 5000, (1, 3, "h", "w"), r"imgsz must be a positive size"),
    ((100_000, 100_000), (1, 3, "h", "w"), r"takes 100000x100000 images, more than 4096 pixels a side"),
    (None, (1, 3, 100_000, 100_000), r"takes 100000x100000 images, more than 4096 pixels a side"),
], ids=["text", "deep", "huge-declared", "huge-graph"])
def test_a_hostile_input_size_is_refused_when_the_model_loads(tmp_path: Path, imgsz, input_shape, message) -> None:
    """Found by the pre-review attack: an imgsz that is not a Python literal was a ValueError traceback, and a model
    declaring 100,000-pixel inputs loaded, to ask for a 120 GB tensor at its first picture."""
    path = write_model(tmp_path / "m.onnx", GOOD, names=NAMES, imgsz=imgsz, input_shape=input_shape)
    with pytest.raises(ModelError, match=message):
        ObbModel.load(path)


def test_class_names_with_markup_and_paths_are_printed_as_they_are(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    names = {0: "[/]<script>x</script>$x$", 1: "../../etc/passwd", 2: "[bold]"}
    path = write_model(tmp_path / "m.onnx", GOOD, names=names)
    assert main(["detector", "check", str(path)]) == 0
    assert "([/]<script>x</script>$x$, ../../etc/passwd, [bold])" in capsys.readouterr().out
