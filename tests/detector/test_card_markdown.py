"""The model card's Markdown carries class names, folders and commands from a dataset as text (found by the
pre-review attack: a class name with `<script>`, `|` or a newline went into the card raw, so a Markdown viewer ran
the HTML and the tables broke; a command holding three backticks closed the card's code block)."""

from __future__ import annotations

from bt_grasp.detector.card import ModelCard
from bt_grasp.detector.evaluate import ClassMetrics, EvalReport

HOSTILE = ("<script>alert(1)</script>", "a|b\nc", "`code` [x](javascript:y)")


def _card() -> ModelCard:
    per_class = tuple(ClassMetrics(n, 3, 2, 0.5, 0.25, 1, 4.0) for n in HOSTILE)
    report = EvalReport(images=4, labels=9, map50=0.5, map50_95=0.25, median_angle_error_deg=4.0, angle_errors=3,
                        per_class=per_class, names=HOSTILE, confusion=tuple((1, 0, 0, 0) for _ in range(4)))
    return ModelCard(
        model_file="m.onnx", sha256="0" * 64, architecture="YOLO11n-OBB", classes=HOSTILE, imgsz=320,
        datasets=({"folder": "<img src=x onerror=y>", "role": "train", "images": 4,
                   "command": "bt-grasp detector dataset ```\n# </pre><script>z</script>"},),
        train_command="bt-grasp detector train", epochs=1, seed=0, training_seconds=1.0, held_out=report,
        eval_command="", ultralytics_metrics={}, versions={}, machine={})


def test_dataset_strings_are_text_in_the_card() -> None:
    text = _card().to_markdown()
    assert text.count("```") == 2  # the shell block opens and closes once (inside it, <script> is only text)
    before, _block, after = text.split("```")
    prose = before + after
    assert "<script>" not in prose and "<img" not in prose and "&lt;script&gt;" in prose
    table = [line for line in text.splitlines() if line.startswith("| ")]
    assert all(line.count(" | ") == table[0].count(" | ") for line in table[:5]), table
    confusion = [line for line in table if line.startswith("| true")] + table[-4:]
    assert len({line.count(" | ") for line in confusion}) == 1, confusion
