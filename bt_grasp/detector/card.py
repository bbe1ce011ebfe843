"""The model card a training run writes beside its ONNX export: ``MODEL_CARD.md`` for people and
``MODEL_CARD.json`` for programs, with the same facts: the classes, the input size, the datasets and the exact
commands that made them, the held-out figures measured through bt_grasp's own inference path, the training time,
the machine, the versions and the licences."""

from __future__ import annotations

import hashlib
import html
import json
import os
import platform
from dataclasses import dataclass, field
from pathlib import Path

from bt_grasp.detector.evaluate import EvalReport
from bt_grasp.files.output_files import write_output_file

CARD_MD = "MODEL_CARD.md"
CARD_JSON = "MODEL_CARD.json"
#: the issue's goals for the shipped model (held-out synthetic validation)
GOAL_MAP50 = 0.90
GOAL_ANGLE_DEG = 5.0

LICENCES = {
    "weights": "AGPL-3.0: the weights were trained with Ultralytics (AGPL-3.0), whose licence its authors apply to "
               "models trained with it unless an Ultralytics Enterprise licence is held; whoever distributes these "
               "weights, or a service running them, owes AGPL-3.0's terms for them",
    "bt_grasp": "BSD-3-Clause: bt_grasp's code, including the inference path (onnxruntime, MIT, and bt_grasp's own "
                "decoder) that runs the weights; Ultralytics is not imported by it",
    "training_data": "bt_grasp's own renders of its own scenes and meshes (BSD-3-Clause with the repository)",
}


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def machine() -> dict[str, object]:
    """What trained the model: processor, cores, the load when asked, operating system."""
    cpu = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text(encoding="utf-8", errors="replace").splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    load = [round(v, 1) for v in os.getloadavg()] if hasattr(os, "getloadavg") else None
    return {"cpu": cpu, "cores": os.cpu_count(), "gpu": "none (CPU training)", "os": platform.platform(),
            "load_average_1_5_15_min_at_end": load}


@dataclass(frozen=True)
class ModelCard:
    model_file: str
    sha256: str
    architecture: str
    classes: tuple[str, ...]
    imgsz: int
    datasets: tuple[dict[str, object], ...]  # {"folder", "images", "command", "role": "train"|"val"}
    train_command: str
    epochs: int
    seed: int
    training_seconds: float
    held_out: EvalReport | None
    eval_command: str
    ultralytics_metrics: dict[str, float]
    versions: dict[str, str]
    machine: dict[str, object]
    licences: dict[str, str] = field(default_factory=lambda: dict(LICENCES))

    def to_json(self) -> dict[str, object]:
        report = self.held_out.to_json() if self.held_out is not None else None
        return {
            "model_file": self.model_file, "sha256": self.sha256, "architecture": self.architecture,
            "task": "obb", "classes": list(self.classes), "imgsz": self.imgsz,
            "input": f"[1, 3, {self.imgsz}, {self.imgsz}] RGB in [0, 1], letterboxed (grey 114)",
            "output": f"[1, {4 + len(self.classes) + 1}, anchors]: cx, cy, w, h (input pixels), class scores "
                      "(sigmoid), angle (rad); no NMS inside",
            "datasets": list(self.datasets), "commands": {"train": self.train_command, "eval": self.eval_command},
            "epochs": self.epochs, "seed": self.seed, "training_seconds": round(self.training_seconds, 1),
            "held_out": report, "goals": {"map50": GOAL_MAP50, "median_angle_error_deg": GOAL_ANGLE_DEG,
                                          "met": self.goals_met()},
            "ultralytics_own_validation_last_epoch": self.ultralytics_metrics,
            "versions": self.versions, "machine": self.machine, "licences": self.licences,
        }

    def goals_met(self) -> bool | None:
        if self.held_out is None:
            return None
        angle = self.held_out.median_angle_error_deg
        return self.held_out.map50 >= GOAL_MAP50 and angle is not None and angle <= GOAL_ANGLE_DEG

    def to_markdown(self) -> str:
        lines = [f"# Model card: {self.model_file}", "",
                 f"A {self.architecture} oriented-box detector of {len(self.classes)} classes, "
                 + ("fine-tuned from the weights named there" if "fine-tuned" in self.architecture else
                    "trained from scratch (no pretrained weights)")
                 + f" on the datasets below, exported to ONNX (input {self.imgsz}x"
                 f"{self.imgsz}) and run by bt_grasp through onnxruntime with its own decoder "
                 "(`bt_grasp.detector.model.ObbModel`).", "",
                 f"- file: `{self.model_file}`, SHA-256 `{self.sha256}`",
                 f"- classes (index order): {', '.join(_md(c) for c in self.classes)}",
                 f"- input: `[1, 3, {self.imgsz}, {self.imgsz}]` RGB in [0, 1], letterboxed with grey 114; output "
                 f"`[1, {4 + len(self.classes) + 1}, anchors]` (cx, cy, w, h in input pixels, sigmoid class "
                 "scores, angle in radians), no NMS inside",
                 "", "## How it was made", "", "```sh"]
        for d in self.datasets:
            lines.append(_code(str(d.get("command") or f"# {d['folder']}: made by hand (no manifest)")))
        lines += [_code(self.train_command), *([_code(self.eval_command)] if self.eval_command else []), "```", ""]
        for d in self.datasets:
            lines.append(f"- {_md(str(d['role']))}: {_md(str(d['folder']))}, {d['images']} pictures")
        lines += [f"- {self.epochs} epochs, seed {self.seed}, training time {self.training_seconds / 60:.1f} min "
                  f"on {self.machine.get('cores')} cores ({self.machine.get('cpu')}, no GPU; load average at the "
                  f"end {self.machine.get('load_average_1_5_15_min_at_end')}, the training's own threads included)",
                  f"- versions: {', '.join(f'{k} {v}' for k, v in self.versions.items())}", ""]
        lines += ["## Held-out figures", ""]
        if self.held_out is None:
            lines.append("None: no held-out dataset was given (`--val`).")
        else:
            r = self.held_out
            angle = "n/a" if r.median_angle_error_deg is None else f"{r.median_angle_error_deg:.1f}°"
            met = self.goals_met()
            lines += [f"Measured by `bt-grasp detector eval` (bt_grasp's inference path) on {r.images} held-out "
                      f"pictures with {r.labels} labels (seeds not used in training):", "",
                      f"- **mAP50 {r.map50:.3f}**, mAP50-95 {r.map50_95:.3f}",
                      f"- **median angle error of elongated objects {angle}** ({r.angle_errors} matched objects)",
                      f"- the issue's goal (mAP50 >= {GOAL_MAP50}, median angle error <= {GOAL_ANGLE_DEG}°): "
                      f"{'met' if met else '**not met**'}", "",
                      "| class | labels | predictions > 0.25 | AP50 | AP50-95 | median angle error (n) |",
                      "| --- | ---: | ---: | ---: | ---: | ---: |"]
            for c in r.per_class:
                ang = "" if c.median_angle_error_deg is None else f"{c.median_angle_error_deg:.1f}° ({c.elongated})"
                lines.append(f"| {_md(c.name)} | {c.labels} | {c.predictions} | {c.ap50:.3f} | {c.ap50_95:.3f} "
                             f"| {ang} |")
            names = [*r.names, "background"]
            lines += ["", "Confusion (rows: true class, columns: predicted; score > 0.25, IoU >= 0.5):", "",
                      "| true \\ predicted | " + " | ".join(_md(n) for n in names) + " |",
                      "| --- |" + " ---: |" * len(names)]
            for name, row in zip(names, r.confusion, strict=True):
                lines.append(f"| {_md(name)} | " + " | ".join(str(v) for v in row) + " |")
        if self.ultralytics_metrics:
            own = ", ".join(f"{k.removeprefix('metrics/')} {v:.3f}" for k, v in self.ultralytics_metrics.items())
            lines += ["", f"Ultralytics' own validation at the last epoch (PyTorch weights, its data loader): {own}"]
        lines += ["", "## Licences", ""]
        lines += [f"- {k.replace('_', ' ')}: {v}" for k, v in self.licences.items()]
        return "\n".join(lines) + "\n"

    def write(self, folder: Path) -> tuple[Path, Path]:

        md = write_output_file(folder / CARD_MD, self.to_markdown(), "--out")
        js = write_output_file(folder / CARD_JSON, json.dumps(self.to_json(), indent=2) + "\n", "--out")
        return md, js


def _md(text: str) -> str:
    """A class name or folder from a dataset as plain Markdown text: no HTML, no table break, no code span, one
    line (a dataset's data.yaml names are whoever made it, not ours)."""
    return html.escape(" ".join(text.split())).replace("|", "\\|").replace("`", "\\`").replace("[", "\\[")


#: a shell line may not close the card's code block
FENCE = "`" * 3


def _code(line: str) -> str:
    """One line of the card's shell block: it cannot close the block or start another line."""
    return " ".join(line.split()).replace(FENCE, "'" * 3)
