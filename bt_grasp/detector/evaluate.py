"""`bt-grasp detector eval`: how well a YOLO-OBB ONNX export finds a dataset's labelled objects, measured through
bt_grasp's own inference path (``ObbModel``: letterbox, onnxruntime, decoder, rotated NMS), i.e. what the pipeline
runs, not what a training framework reports.

The metric math follows Ultralytics' OBB validator so the figures compare with its own:

- predictions at ``conf`` 0.01 (Ultralytics' OBB validation threshold), NMS IoU 0.7, at most 300 per image;
- overlap is the probabilistic IoU of the boxes seen as Gaussians (``batch_probiou``), as Ultralytics' OBB
  validator matches;
- at each IoU threshold 0.50, 0.55, ..., 0.95 a prediction (in descending score) is a true positive when it takes
  the best still unclaimed label of its class at that IoU or more (``match_predictions``);
- average precision per class: the precision envelope integrated over 101 recall points (COCO); mAP is the mean
  over the classes that have labels (a class with no label is not averaged in).

Beside them, at the pipeline's own threshold (score above 0.25) and IoU 0.5:

- the angle error of elongated objects (a label whose long side is at least 1.5 x its short side): the angle
  between the long axes of the label and of the prediction matched to it (same class), in [0, 90] degrees;
- the confusion between classes: labels and predictions matched one to one by IoU whatever their classes (the
  highest overlaps first); rows are the true class, columns the predicted class, the last row and column
  "background" (a prediction with no label, a label with no prediction).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.obb import DEFAULT_CONF, batch_probiou
from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.config import read_yaml
from bt_grasp.files.image_header import image_size

#: Ultralytics' OBB validation thresholds
EVAL_CONF = 0.01
EVAL_IOU_NMS = 0.7
IOU_THRESHOLDS = np.linspace(0.5, 0.95, 10)
#: a label is elongated (its direction is defined) when its long side is at least this many times its short side
ELONGATED_RATIO = 1.5
#: the overlap at which angle errors and the confusion matrix pair labels with predictions
MATCH_IOU = 0.5
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp")


class DatasetError(InputError):
    """A dataset folder is missing, incomplete or does not fit the model."""


@dataclass(frozen=True)
class Boxes:
    """Oriented boxes of one image: ``xywhr`` (N, 5) in pixels and radians, ``classes`` (N,), ``scores`` (N,)
    (1 for labels)."""

    xywhr: NDArray[np.float64]
    classes: NDArray[np.intp]
    scores: NDArray[np.float64]

    @classmethod
    def empty(cls) -> Boxes:
        return cls(np.zeros((0, 5)), np.zeros((0,), dtype=np.intp), np.zeros((0,)))

    @classmethod
    def of(cls, xywhr: Sequence[Sequence[float]] | Sequence[NDArray[np.float64]], classes: Sequence[int],
           scores: Sequence[float] | None = None) -> Boxes:
        boxes = np.asarray(xywhr, dtype=np.float64).reshape(-1, 5)
        return cls(boxes, np.asarray(classes, dtype=np.intp).reshape(-1),
                   np.ones(len(boxes)) if scores is None else np.asarray(scores, dtype=np.float64).reshape(-1))


@dataclass(frozen=True)
class ClassMetrics:
    name: str
    labels: int
    predictions: int  # above the pipeline's threshold (0.25)
    ap50: float
    ap50_95: float
    elongated: int  # elongated labels matched by a prediction of their class (the angle errors' count)
    median_angle_error_deg: float | None
    scored: int = 0  # the predictions AP scores: every one the model gave at EVAL_CONF (0.01) or more


@dataclass(frozen=True)
class EvalReport:
    """mAP over the classes with labels, the median angle error over every elongated matched label, per class
    figures, and the confusion matrix (rows: true class then background; columns: predicted class then
    background)."""

    images: int
    labels: int
    map50: float
    map50_95: float
    median_angle_error_deg: float | None
    angle_errors: int
    per_class: tuple[ClassMetrics, ...]
    names: tuple[str, ...]
    confusion: tuple[tuple[int, ...], ...]

    def to_json(self) -> dict[str, object]:
        return {
            "images": self.images, "labels": self.labels, "map50": self.map50, "map50_95": self.map50_95,
            "median_angle_error_deg": self.median_angle_error_deg, "angle_errors": self.angle_errors,
            "per_class": [vars(c) for c in self.per_class],
            "confusion": {"rows": "true class", "columns": "predicted class", "labels": [*self.names, "background"],
                          "matrix": [list(r) for r in self.confusion]},
            "method": {"conf": EVAL_CONF, "nms_iou": EVAL_IOU_NMS, "iou": "probabilistic (batch_probiou)",
                       "ap": "101-point envelope (COCO), mean over classes with labels",
                       "angle_and_confusion": {"score_above": DEFAULT_CONF, "iou": MATCH_IOU,
                                               "elongated_ratio": ELONGATED_RATIO}},
        }


def compute_ap(recall: NDArray[np.float64], precision: NDArray[np.float64]) -> float:
    """Average precision: the precision envelope (each precision raised to the best at higher recall) integrated
    by the trapezoidal rule over 101 recall points 0, 0.01, ..., 1, as COCO and Ultralytics do."""
    last = recall[-1] if len(recall) else 1.0
    mrec = np.concatenate(([0.0], recall, [last], [1.0]))
    mpre = np.concatenate(([1.0], precision, [0.0], [0.0]))
    mpre = np.flip(np.maximum.accumulate(np.flip(mpre)))
    x = np.linspace(0.0, 1.0, 101)
    return float(np.trapezoid(np.interp(x, mrec, mpre), x))


def match_predictions(pred: Boxes, truth: Boxes) -> NDArray[np.bool_]:
    """(N predictions, 10 thresholds): whether each prediction, taken in descending score, claims the best still
    unclaimed label of its class at IoU >= the threshold."""
    correct = np.zeros((len(pred.classes), len(IOU_THRESHOLDS)), dtype=bool)
    if len(pred.classes) == 0 or len(truth.classes) == 0:
        return correct
    order = np.argsort(-pred.scores, kind="stable")
    iou = batch_probiou(truth.xywhr, pred.xywhr[order]) * (truth.classes[:, None] == pred.classes[order][None, :])
    matched = np.zeros((len(truth.classes), len(IOU_THRESHOLDS)), dtype=bool)
    cols = np.arange(len(IOU_THRESHOLDS))
    for j in np.flatnonzero((iou >= IOU_THRESHOLDS.min()).any(axis=0)):
        available = np.where(matched, 0.0, iou[:, j, None])
        k = available.argmax(axis=0)
        hit = available[k, cols] >= IOU_THRESHOLDS
        correct[order[j]] = hit
        matched[k, cols] |= hit
    return correct


def _one_to_one(iou: NDArray[np.float64], threshold: float) -> list[tuple[int, int]]:
    """(label, prediction) pairs with IoU >= threshold, highest IoU first, each label and prediction used once."""
    pairs = np.argwhere(iou >= threshold)
    pairs = pairs[np.argsort(-iou[pairs[:, 0], pairs[:, 1]], kind="stable")] if len(pairs) else pairs
    used_t: set[int] = set()
    used_p: set[int] = set()
    out = []
    for t, p in pairs:
        if int(t) not in used_t and int(p) not in used_p:
            used_t.add(int(t))
            used_p.add(int(p))
            out.append((int(t), int(p)))
    return out


def long_axis_rad(xywhr: NDArray[np.float64]) -> NDArray[np.float64]:
    """Direction of each box's long side, in [0, pi)."""
    return np.asarray(np.mod(xywhr[:, 4] + np.where(xywhr[:, 2] >= xywhr[:, 3], 0.0, math.pi / 2), math.pi))


def axis_error_deg(a_rad: NDArray[np.float64], b_rad: NDArray[np.float64]) -> NDArray[np.float64]:
    """The angle between two undirected axes, in [0, 90] degrees."""
    d = np.mod(np.asarray(a_rad) - np.asarray(b_rad), math.pi)
    return np.asarray(np.degrees(np.minimum(d, math.pi - d)))


def evaluate(truths: Sequence[Boxes], preds: Sequence[Boxes], names: Sequence[str]) -> EvalReport:
    """The report for one prediction set per image (``preds[i]`` against ``truths[i]``)."""
    nc = len(names)
    tp_all, conf_all, cls_all, target_cls = [], [], [], []
    confusion = np.zeros((nc + 1, nc + 1), dtype=np.int64)
    angle_errors: dict[int, list[float]] = {c: [] for c in range(nc)}
    for truth, pred in zip(truths, preds, strict=True):
        tp_all.append(match_predictions(pred, truth))
        conf_all.append(pred.scores)
        cls_all.append(pred.classes)
        target_cls.append(truth.classes)
        sure = pred.scores > DEFAULT_CONF
        p_boxes, p_cls = pred.xywhr[sure], pred.classes[sure]
        iou = batch_probiou(truth.xywhr, p_boxes) if len(truth.classes) and len(p_cls) else np.zeros(
            (len(truth.classes), len(p_cls)))
        pairs = _one_to_one(iou, MATCH_IOU)
        for t, p in pairs:
            confusion[truth.classes[t], p_cls[p]] += 1
        for t in set(range(len(truth.classes))) - {t for t, _ in pairs}:
            confusion[truth.classes[t], nc] += 1
        for p in set(range(len(p_cls))) - {p for _, p in pairs}:
            confusion[nc, p_cls[p]] += 1
        same = iou * (truth.classes[:, None] == p_cls[None, :]) if iou.size else iou
        for t, p in _one_to_one(same, MATCH_IOU):
            w, h = truth.xywhr[t, 2], truth.xywhr[t, 3]
            if max(w, h) >= ELONGATED_RATIO * max(min(w, h), 1e-9):
                err = axis_error_deg(long_axis_rad(truth.xywhr[t : t + 1]), long_axis_rad(p_boxes[p : p + 1]))
                angle_errors[int(truth.classes[t])].append(float(err[0]))
    tp = np.concatenate(tp_all) if tp_all else np.zeros((0, len(IOU_THRESHOLDS)), dtype=bool)
    conf = np.concatenate(conf_all) if conf_all else np.zeros((0,))
    pred_cls = np.concatenate(cls_all) if cls_all else np.zeros((0,), dtype=np.intp)
    targets = np.concatenate(target_cls) if target_cls else np.zeros((0,), dtype=np.intp)
    order = np.argsort(-conf, kind="stable")
    tp, conf, pred_cls = tp[order], conf[order], pred_cls[order]
    per_class, aps = [], []
    for c in range(nc):
        n_labels = int((targets == c).sum())
        mine = pred_cls == c
        ap = np.zeros(len(IOU_THRESHOLDS))
        if n_labels and mine.any():
            tpc = tp[mine].cumsum(axis=0)
            fpc = (1 - tp[mine]).cumsum(axis=0)
            recall = tpc / n_labels
            precision = tpc / (tpc + fpc)
            ap = np.array([compute_ap(recall[:, j], precision[:, j]) for j in range(len(IOU_THRESHOLDS))])
        if n_labels:
            aps.append(ap)
        errs = angle_errors[c]
        per_class.append(ClassMetrics(names[c], n_labels, int(((pred_cls == c) & (conf > DEFAULT_CONF)).sum()),
                                      float(ap[0]), float(ap.mean()), len(errs),
                                      float(np.median(errs)) if errs else None, scored=int(mine.sum())))
    every_error = [e for c in range(nc) for e in angle_errors[c]]
    ap_table = np.array(aps) if aps else np.zeros((0, len(IOU_THRESHOLDS)))
    return EvalReport(
        images=len(truths), labels=len(targets),
        map50=float(ap_table[:, 0].mean()) if len(ap_table) else 0.0,
        map50_95=float(ap_table.mean()) if len(ap_table) else 0.0,
        median_angle_error_deg=float(np.median(every_error)) if every_error else None,
        angle_errors=len(every_error), per_class=tuple(per_class), names=tuple(names),
        confusion=tuple(tuple(int(v) for v in row) for row in confusion),
    )


# --- datasets on disk --------------------------------------------------------------------------------------------

def corners_to_xywhr(corners: NDArray[np.float64]) -> NDArray[np.float64]:
    """(4, 2) corners -> xywhr by ``cv2.minAreaRect`` (as Ultralytics reads OBB labels)."""
    (cx, cy), (w, h), angle = cv2.minAreaRect(np.asarray(corners, dtype=np.float32).reshape(-1, 2))
    return np.array([cx, cy, w, h, math.radians(angle)], dtype=np.float64)


def dataset_names(folder: Path) -> tuple[str, ...]:
    """A dataset folder's class names from its ``data.yaml``; a missing or bad one is a one-sentence error."""
    if not folder.is_dir():
        raise DatasetError(folder, "no such dataset folder (make one with `bt-grasp detector dataset`)")
    data = folder / "data.yaml"
    if not data.is_file():
        raise DatasetError(folder, "is not a dataset: it has no data.yaml (make one with `bt-grasp detector dataset`)")

    try:
        doc, _ = read_yaml(data)  # bounded: size, nesting, aliases
    except InputError as exc:
        raise DatasetError(data, f"cannot be read: {exc.problem}") from None
    raw = doc.get("names") if isinstance(doc, dict) else None
    if isinstance(raw, list) and raw and all(isinstance(n, str) for n in raw):
        return tuple(raw)
    if isinstance(raw, dict) and raw and sorted(raw) == list(range(len(raw))) and all(
            isinstance(v, str) for v in raw.values()):
        return tuple(raw[i] for i in range(len(raw)))
    raise DatasetError(data, "'names' must be a list of class names or a mapping 0, 1, 2, ... -> name", "names")


def dataset_images(folder: Path) -> list[Path]:
    """The images of a dataset folder (``images/``), sorted; none is an error."""
    images = sorted(p for p in (folder / "images").glob("*") if p.suffix.lower() in IMAGE_SUFFIXES)
    if not images:
        raise DatasetError(folder, "has no images in images/")
    return images


#: a dataset picture's largest side: bigger ones are refused before they are decoded
MAX_DATASET_IMAGE_SIDE = 8192
#: and its largest file
MAX_DATASET_IMAGE_BYTES = 64 << 20


def read_image(path: Path) -> NDArray[np.uint8]:
    """One dataset picture (BGR), read bounded: a regular file of at most 64 MB whose header (PNG, JPEG) says at
    most 8192 pixels a side, so a FIFO, a link to /dev/zero or a small file saying 50,000 x 50,000 is one
    sentence, not a hang or an exhausted machine (found by the pre-review attack)."""

    data = read_user_file(path, MAX_DATASET_IMAGE_BYTES, error=DatasetError)
    size = image_size(data)
    if size is not None and max(size) > MAX_DATASET_IMAGE_SIDE:
        raise DatasetError(path, f"says it is {size[0]} x {size[1]} pixels, more than {MAX_DATASET_IMAGE_SIDE} a side")
    if size is None and path.suffix.lower() != ".bmp":  # a BMP is not compressed: its file bounds its pixels
        raise DatasetError(path, "is not a PNG or JPEG image")
    bgr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if bgr is None:
        raise DatasetError(path, "cannot be read as an image")
    return np.asarray(bgr, dtype=np.uint8)


def read_labels(label_file: Path, width_px: int, height_px: int, nc: int) -> Boxes:
    """One image's label file as boxes in pixels; a malformed line is a one-sentence error naming it."""
    if not label_file.is_file():
        raise DatasetError(label_file, "no such label file (every image needs one; empty for no object)")
    xywhr, classes = [], []

    try:
        text = read_user_file(label_file, error=DatasetError).decode("utf-8")  # bounded: no FIFO, no giant file
    except UnicodeDecodeError:
        raise DatasetError(label_file, "is not UTF-8 text") from None
    for number, line in enumerate(text.splitlines(), start=1):
        parts = line.split()
        if not parts:
            continue
        try:
            values = [float(v) for v in parts[1:]]
            cls = int(parts[0])
        except ValueError:
            raise DatasetError(label_file, "expected 'class x1 y1 x2 y2 x3 y3 x4 y4' (numbers)", number) from None
        if len(values) != 8:
            raise DatasetError(label_file, f"expected 'class x1 y1 x2 y2 x3 y3 x4 y4', got {len(parts)} fields",
                               number)
        if not 0 <= cls < nc:
            raise DatasetError(label_file, f"class {cls} is not one of the dataset's {nc} classes", number)
        corners = np.array(values).reshape(4, 2) * np.array([width_px, height_px], dtype=np.float64)
        xywhr.append(corners_to_xywhr(corners))
        classes.append(cls)
    return Boxes.of(xywhr, classes) if classes else Boxes.empty()


def check_same_classes(model_names: Sequence[str], model: Path, names: Sequence[str], data: Path) -> None:
    if tuple(model_names) != tuple(names):
        raise DatasetError(model, f"its classes ({', '.join(model_names)}) are not the dataset's "
                                  f"{data / 'data.yaml'} classes ({', '.join(names)}) in the same order")


def evaluate_model(model_path: Path, dataset: Path, *, imgsz: int | None = None) -> EvalReport:
    """Run ``model_path`` through bt_grasp's inference path on every image of ``dataset`` and score it."""
    from bt_grasp.detector.model import ObbModel  # deferred: onnxruntime loads only when a model is evaluated

    names = dataset_names(dataset)
    images = dataset_images(dataset)
    model = ObbModel.load(model_path, imgsz=imgsz)
    check_same_classes(model.names, model_path, names, dataset)
    truths, preds = [], []
    for image in images:
        bgr = read_image(image)
        rgb = np.ascontiguousarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), dtype=np.uint8)
        truths.append(read_labels(dataset / "labels" / f"{image.stem}.txt", rgb.shape[1], rgb.shape[0], len(names)))
        found = model.detect(rgb, conf=EVAL_CONF, iou=EVAL_IOU_NMS)
        preds.append(Boxes.of([[d.cx_px, d.cy_px, d.width_px, d.height_px, d.angle_rad] for d in found],
                              [d.class_id for d in found], [d.score for d in found]))
    return evaluate(truths, preds, names)


def format_report(report: EvalReport) -> str:
    """The report as text (80 columns): the totals, a table per class, the confusion matrix. The table's
    ``preds`` are the predictions its AP scores (score >= 0.01, as Ultralytics validates); ``> 0.25`` those the
    pipeline keeps, which the angle errors and the confusion matrix pair with labels."""
    angle = "n/a" if report.median_angle_error_deg is None else f"{report.median_angle_error_deg:.1f} deg"
    lines = [f"{report.images} images, {report.labels} labels: mAP50 {report.map50:.3f}, mAP50-95 "
             f"{report.map50_95:.3f},",
             f"median angle error of elongated objects {angle} ({report.angle_errors})",
             f"preds: the predictions AP scores (score >= {EVAL_CONF:g}); > {DEFAULT_CONF:g}: those the",
             "pipeline keeps (the angle errors and the confusion matrix pair only these)",
             f"{'class':<12} {'labels':>6} {'preds':>6} {'> ' + format(DEFAULT_CONF, 'g'):>6} {'AP50':>6} "
             f"{'AP50-95':>7} {'angle deg (n)':>14}"]
    for c in report.per_class:
        if not c.labels and not c.scored and not c.predictions:
            continue
        ang = "-" if c.median_angle_error_deg is None else f"{c.median_angle_error_deg:.1f} ({c.elongated})"
        lines.append(f"{c.name[:12]:<12} {c.labels:>6} {c.scored:>6} {c.predictions:>6} {c.ap50:>6.3f} "
                     f"{c.ap50_95:>7.3f} {ang:>14}")
    used = [i for i in range(len(report.names)) if any(report.confusion[i]) or any(r[i] for r in report.confusion)]
    used.append(len(report.names))
    labels = [*report.names, "backgr"]
    lines.append(f"confusion (rows: true, columns: predicted, score > {DEFAULT_CONF:g}, IoU >= {MATCH_IOU:g}):")
    lines.append(" " * 12 + "".join(f"{labels[j][:7]:>8}" for j in used))
    for i in used:
        lines.append(f"{labels[i][:12]:<12}" + "".join(f"{report.confusion[i][j]:>8}" for j in used))
    return "\n".join(lines)
