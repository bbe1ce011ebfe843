"""A YOLO-OBB ONNX export behind an onnxruntime session: checked when loaded, one sentence per problem.

onnxruntime is imported here, inside ``ObbModel.load``: nothing imports this module unless a learned detector is
asked for. Class names come from the export's metadata (Ultralytics writes ``names`` as a Python dict literal,
``{0: 'mug', 1: 'banana'}``) or, for an export without it, from a sidecar card ``<model>.card.yaml`` beside the
model with ``names:`` (a list, or a mapping index -> name) and optionally ``imgsz:``.
"""

from __future__ import annotations

import ast
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.letterbox import letterbox, to_input_tensor
from bt_grasp.detector.obb import DEFAULT_CONF, DEFAULT_IOU, OrientedDetection, decode
from bt_grasp.errors import InputError, did_you_mean

#: onnxruntime threads for one model: 1 is steadier than 2 on a busy 2-core machine (PLATFORM-NOTES)
DEFAULT_THREADS = 1
#: the largest input side a model may declare: YOLO exports are 320-1536 px; a model declaring 100,000 px took a
#: 120 GB input tensor at its first picture
MAX_INPUT_SIDE = 4096


class ModelError(InputError):
    """A detector model file is not a usable YOLO-OBB export, or was asked for something it does not have."""


def card_path(model_path: Path) -> Path:
    """Where the sidecar card of ``model_path`` lives: ``best.onnx`` -> ``best.card.yaml``."""
    return model_path.with_name(model_path.stem + ".card.yaml")


def _parse_names(raw: object, source: Path, where: str) -> tuple[str, ...]:
    """``names`` as a list or a mapping {0: 'a', 1: 'b'} (indices 0..n-1, each once) -> names in index order."""
    if isinstance(raw, list | tuple) and raw and all(isinstance(n, str) and n for n in raw):
        return tuple(raw)
    if isinstance(raw, dict) and raw:
        try:
            indexed = {int(k): v for k, v in raw.items()}
        except (TypeError, ValueError):
            raise ModelError(source, "class names must be indexed 0, 1, 2, ...", where) from None
        if sorted(indexed) != list(range(len(indexed))) or not all(isinstance(v, str) and v for v in indexed.values()):
            raise ModelError(source, "class names must be non-empty strings indexed 0, 1, 2, ... without gaps", where)
        return tuple(indexed[i] for i in range(len(indexed)))
    raise ModelError(source, "class names must be a non-empty list of names or a mapping index -> name", where)


def _read_card(path: Path) -> dict[str, Any]:
    from bt_grasp.files.config import read_yaml

    try:
        data, _ = read_yaml(path)  # bounded: size, nesting, aliases
    except InputError as exc:
        raise ModelError(path, f"cannot be read as a model card: {exc.problem}") from None
    if not isinstance(data, dict):
        raise ModelError(path, "is not a mapping with 'names'")
    return data


def _imgsz(raw: object, source: Path, where: str) -> tuple[int, int]:
    try:
        value = ast.literal_eval(raw) if isinstance(raw, str) else raw
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        value = None
    if isinstance(value, int) and value > 0:
        return (value, value)
    if isinstance(value, list | tuple) and len(value) == 2 and all(isinstance(v, int) and v > 0 for v in value):
        return (int(value[0]), int(value[1]))
    raise ModelError(source, f"imgsz must be a positive size or [height, width], got {raw!r}", where)


@dataclass(frozen=True)
class ModelInfo:
    """What a loaded model is: its input size (height, width), class names in index order, anchors."""

    path: Path
    input_hw: tuple[int, int]
    names: tuple[str, ...]
    anchors: int | None  # None when the export's anchor dimension is dynamic


class ObbModel:
    """An onnxruntime session over a YOLO-OBB export: ``detect(rgb)`` -> oriented detections."""

    def __init__(self, session: Any, info: ModelInfo, input_name: str) -> None:
        self._session = session
        self.info = info
        self._input_name = input_name

    @property
    def names(self) -> tuple[str, ...]:
        return self.info.names

    @classmethod
    def load(cls, path: str | Path, *, imgsz: int | tuple[int, int] | None = None,
             threads: int = DEFAULT_THREADS) -> ObbModel:
        """Open and check ``path``. ``imgsz`` (when given) must match the model's fixed input size."""
        path = Path(path)
        if not path.is_file():
            raise ModelError(path, "no such model file")
        import onnxruntime as ort

        options = ort.SessionOptions()
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        options.log_severity_level = 3  # errors only: a user's model's warnings are not ours to print
        try:
            session = ort.InferenceSession(str(path), sess_options=options, providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own untyped errors for any unreadable file
            first = str(exc).strip().splitlines()[0][:160] if str(exc).strip() else type(exc).__name__
            raise ModelError(path, f"is not an ONNX model onnxruntime can open ({first})") from None
        inputs, outputs = session.get_inputs(), session.get_outputs()
        metadata = dict(session.get_modelmeta().custom_metadata_map)
        card = card_path(path)
        card_data = _read_card(card) if card.is_file() else {}
        if "names" in metadata:
            names = _parse_names(_literal(metadata["names"], path), path, "metadata 'names'")
        elif "names" in card_data:
            names = _parse_names(card_data["names"], card, "names")
        else:
            raise ModelError(path, f"has no class names: neither 'names' in its ONNX metadata nor a card {card.name}")
        if len(inputs) != 1 or len(inputs[0].shape) != 4 or inputs[0].shape[1] not in (3, "3"):
            shapes = [list(i.shape) for i in inputs]
            raise ModelError(path, f"is not a YOLO-OBB export: expected one image input [1, 3, H, W], got {shapes}")
        input_hw = _model_input_hw(inputs[0].shape, metadata, card_data, path, card)
        if imgsz is not None:
            wanted = (imgsz, imgsz) if isinstance(imgsz, int) else tuple(imgsz)
            if wanted != input_hw:
                raise ModelError(path, f"takes {input_hw[0]}x{input_hw[1]} images, not the "
                                       f"{wanted[0]}x{wanted[1]} asked for (re-export it at that size)")
        anchors = _check_output(outputs, len(names), path)
        return cls(session, ModelInfo(path, input_hw, names, anchors), inputs[0].name)

    def class_id(self, name: str, source: str = "class") -> int:
        """The index of class ``name``; an unknown name is a one-sentence error with the closest known name."""
        if name in self.names:
            return self.names.index(name)
        hint = did_you_mean(name, self.names)
        raise ModelError(source, f"the model {self.info.path.name} has no class '{name}'{hint}"
                                 f" (its classes: {', '.join(self.names)})")

    def raw_output(self, rgb: NDArray[np.uint8]) -> tuple[NDArray[np.float32], Any]:
        """Letterbox ``rgb`` and run the network: (raw output, letterbox geometry)."""
        boxed, geometry = letterbox(rgb, self.info.input_hw)
        (output,) = self._session.run(None, {self._input_name: to_input_tensor(boxed)})
        return np.asarray(output, dtype=np.float32), geometry

    def detect(self, rgb: NDArray[np.uint8], *, conf: float = DEFAULT_CONF, iou: float = DEFAULT_IOU,
               classes: Sequence[str] | None = None) -> list[OrientedDetection]:
        """Oriented detections in ``rgb``'s pixels, best first; ``classes`` keeps only those names."""
        wanted = None if classes is None else {self.class_id(c) for c in classes}
        output, geometry = self.raw_output(rgb)
        if output.ndim != 3 or output.shape[1] != 4 + len(self.names) + 1:
            raise ModelError(self.info.path, f"produced an output of shape {list(output.shape)}, not "
                                             f"[1, {4 + len(self.names) + 1}, anchors]")
        found = decode(output, self.names, geometry, conf=conf, iou=iou)
        return found if wanted is None else [d for d in found if d.class_id in wanted]


def _literal(raw: str, path: Path) -> object:
    try:
        return ast.literal_eval(raw)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        raise ModelError(path, "its metadata 'names' is not a list or mapping of class names") from None


def _model_input_hw(shape: Sequence[object], metadata: dict[str, str], card: dict[str, Any], path: Path,
                    card_file: Path) -> tuple[int, int]:
    h, w = shape[2], shape[3]
    fixed = (h, w) if isinstance(h, int) and isinstance(w, int) and h > 0 and w > 0 else None
    declared: tuple[int, int] | None = None
    if "imgsz" in metadata:
        declared = _imgsz(metadata["imgsz"], path, "metadata 'imgsz'")
    elif "imgsz" in card:
        declared = _imgsz(card["imgsz"], card_file, "imgsz")
    if fixed is not None and declared is not None and fixed != declared:
        raise ModelError(path, f"says its input is {declared[0]}x{declared[1]} but its graph takes "
                               f"{fixed[0]}x{fixed[1]}")
    size = fixed if fixed is not None else declared
    if size is None:
        raise ModelError(path, "has a dynamic input size and no 'imgsz' in its metadata or card")
    if max(size) > MAX_INPUT_SIDE:
        raise ModelError(path, f"takes {size[0]}x{size[1]} images, more than {MAX_INPUT_SIDE} pixels a side "
                               "(YOLO-OBB exports take 320 to 1536)")
    return size


def _check_output(outputs: Sequence[Any], nc: int, path: Path) -> int | None:
    """The one output must be [1, 4 + nc + 1, anchors] (rank 3, channels first); returns anchors or None."""
    if len(outputs) != 1:
        raise ModelError(path, f"is not a YOLO-OBB export: it has {len(outputs)} outputs, expected one "
                               f"[1, {4 + nc + 1}, anchors]")
    shape = list(outputs[0].shape)
    if len(shape) != 3:
        raise ModelError(path, f"is not a YOLO-OBB export: its output has rank {len(shape)} ({shape}), expected "
                               f"[1, {4 + nc + 1}, anchors]")
    channels = shape[1]
    if isinstance(channels, int) and channels != 4 + nc + 1:
        if shape[2] == 4 + nc + 1:
            problem = f"its output {shape} is anchors-first; expected channels first [1, {4 + nc + 1}, anchors]"
        elif channels == 4 + nc:
            problem = (f"its output {shape} has no angle channel: a detection (not OBB) export for {nc} classes")
        else:
            problem = f"its output {shape} does not fit {nc} classes: expected [1, {4 + nc + 1}, anchors]"
        raise ModelError(path, f"is not a YOLO-OBB export: {problem}")
    anchors = shape[2]
    return anchors if isinstance(anchors, int) else None
