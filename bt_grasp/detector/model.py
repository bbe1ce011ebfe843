"""A YOLO-OBB ONNX export behind an onnxruntime session: checked when loaded, one sentence per problem.

onnxruntime is imported here, inside ``ObbModel.load``: nothing imports this module unless a learned detector is
asked for. Class names come from the export's metadata (Ultralytics writes ``names`` as a Python dict literal,
``{0: 'mug', 1: 'banana'}``) or, for an export without it, from a sidecar card ``<model>.card.yaml`` beside the
model with ``names:`` (a list, or a mapping index -> name) and optionally ``imgsz:``.

**A model file is not trusted** (a 315-byte model allocated 6.6 GB at its first inference and failed inside
onnxruntime with a traceback). Before onnxruntime sees it, the file is read by the bounded reader (a regular file
of at most 256 MB) and checked with ONNX's own shape inference (:func:`check_graph`): its input is fixed to the size
bt_grasp will feed, and then every tensor of the graph must have a static shape and at most
:data:`MAX_TENSOR_BYTES`; weights kept in external files are refused. onnxruntime then gets only these bytes,
never a path, and the model's first inference runs in a child process under :data:`FIRST_INFERENCE_MEMORY_BYTES`
of address space and :data:`FIRST_INFERENCE_TIMEOUT_S` (an operator's workspace is not a tensor shape inference
sees); a model that passes is remembered by its content for the process's life.
"""

from __future__ import annotations

import ast
import hashlib
import io
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.letterbox import letterbox, to_input_tensor
from bt_grasp.detector.obb import DEFAULT_CONF, DEFAULT_IOU, OrientedDetection, decode
from bt_grasp.errors import InputError, did_you_mean
from bt_grasp.files.bounded_io import MAX_MODEL_BYTES, read_user_file
from bt_grasp.files.config import read_yaml

#: onnxruntime threads for one model: 1 is steadier than 2 on a busy 2-core machine (PLATFORM-NOTES)
DEFAULT_THREADS = 1
#: the largest input side a model may declare: YOLO exports are 320-1536 px; a model declaring 100,000 px took a
#: 120 GB input tensor at its first picture
MAX_INPUT_SIDE = 4096
#: the largest tensor a model's graph may hold once its input is fixed: a YOLO-OBB export at 1536 px holds at most
#: about 230 MB in one tensor (its first convolution's output), the 320 px model shipped here 1.6 MB
MAX_TENSOR_BYTES = 256 << 20
#: the most nodes a model's graphs may hold (a YOLO-OBB export has a few hundred to a few thousand): shape inference's
#: time grows with them
MAX_MODEL_NODES = 50_000
#: the address space and time the first inference of a model may use, in a child process
FIRST_INFERENCE_MEMORY_BYTES = 2 << 30
FIRST_INFERENCE_TIMEOUT_S = 120.0
#: models whose first inference passed, by content (sha256): checked once per process
_checked: set[str] = set()


def forget_checked_models() -> None:
    """Forget which models passed their first inference (tests)."""
    _checked.clear()


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
        if not path.exists() and not path.is_symlink():
            raise ModelError(path, "no such model file")
        data = read_user_file(path, MAX_MODEL_BYTES, error=ModelError)  # a regular file: not a FIFO, not /dev/zero
        graph = _parse(data, path)
        metadata = {p.key: p.value for p in graph.metadata_props}
        card = card_path(path)
        card_data = _read_card(card) if card.is_file() else {}
        if "names" in metadata:
            names = _parse_names(_literal(metadata["names"], path), path, "metadata 'names'")
        elif "names" in card_data:
            names = _parse_names(card_data["names"], card, "names")
        else:
            raise ModelError(path, f"has no class names: neither 'names' in its ONNX metadata nor a card {card.name}")
        inputs = [i for i in graph.graph.input if i.name not in {t.name for t in graph.graph.initializer}]
        shape = _declared_shape(inputs[0]) if len(inputs) == 1 else []
        if len(inputs) != 1 or len(shape) != 4 or shape[1] not in (3, "3"):
            shapes = [_declared_shape(i) for i in inputs]
            raise ModelError(path, f"is not a YOLO-OBB export: expected one image input [1, 3, H, W], got {shapes}")
        input_hw = _model_input_hw(shape, metadata, card_data, path, card)
        if imgsz is not None:
            wanted = (imgsz, imgsz) if isinstance(imgsz, int) else tuple(imgsz)
            if wanted != input_hw:
                raise ModelError(path, f"takes {input_hw[0]}x{input_hw[1]} images, not the "
                                       f"{wanted[0]}x{wanted[1]} asked for (re-export it at that size)")
        checked = check_graph(graph, inputs[0].name, input_hw, path)
        ort = _onnxruntime()
        options = _session_options(ort, threads)
        try:
            session = ort.InferenceSession(checked, sess_options=options, providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own untyped errors for any unreadable file
            first = str(exc).strip().splitlines()[0][:160] if str(exc).strip() else type(exc).__name__
            raise ModelError(path, f"is not an ONNX model onnxruntime can open ({first})") from None
        anchors = _check_output(session.get_outputs(), len(names), path)
        first_inference(checked, inputs[0].name, input_hw, path)
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


def _onnxruntime() -> Any:
    """onnxruntime, imported with ``TMPDIR`` pointing at a private folder that is removed afterwards: its telemetry
    library writes a ``.ses`` file into ``TMPDIR`` when it is imported (onnxruntime 1.32, on Linux), a file in
    the user's temporary folder that nothing asked for."""
    if "onnxruntime" in sys.modules:
        return sys.modules["onnxruntime"]
    private = tempfile.mkdtemp(prefix="bt_grasp_ort_")
    before = os.environ.get("TMPDIR")
    os.environ["TMPDIR"] = private
    try:
        import onnxruntime
    finally:
        if before is None:
            os.environ.pop("TMPDIR", None)
        else:
            os.environ["TMPDIR"] = before
        shutil.rmtree(private, ignore_errors=True)
    return onnxruntime


def _session_options(ort: Any, threads: int) -> Any:
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3  # errors only: a user's model's warnings are not ours to print
    return options


def _parse(data: bytes, path: Path) -> Any:
    """The model's protobuf, read by ONNX's own reader (the file was read bounded)."""
    import onnx

    try:
        model = onnx.load_model_from_string(data)
    except Exception:  # protobuf's own errors for bytes that are not a model
        raise ModelError(path, "is not an ONNX model onnxruntime can open (its protobuf cannot be read)") from None
    if not model.HasField("graph"):
        raise ModelError(path, "is not an ONNX model onnxruntime can open (it has no graph)")
    return model


def _declared_shape(value: Any) -> list[object]:
    """An input's declared shape: numbers, names of dynamic dimensions, or '?' where it says nothing."""
    dims = value.type.tensor_type.shape.dim
    return [d.dim_value if d.HasField("dim_value") else (d.dim_param or "?") for d in dims]


def _graphs(graph: Any) -> list[Any]:
    """A graph and every subgraph of its nodes' attributes (If, Loop, Scan), by iteration."""
    found, stack = [], [graph]
    while stack:
        g = stack.pop()
        found.append(g)
        for node in g.node:
            for attribute in node.attribute:
                stack.extend([attribute.g] if attribute.HasField("g") else [])
                stack.extend(attribute.graphs)
    return found


def check_graph(model: Any, input_name: str, input_hw: tuple[int, int], path: Path) -> bytes:
    """The model's bytes with its image input fixed to ``[1, 3, H, W]`` (what bt_grasp feeds it), once ONNX's shape
    inference (strict, with data propagation) gives every tensor of every graph in it a static shape of at most
    :data:`MAX_TENSOR_BYTES`, and no weight lives in an external file; else one sentence."""
    import onnx
    from onnx import TensorProto, helper

    graphs = _graphs(model.graph)
    nodes = sum(len(g.node) for g in graphs)
    if nodes > MAX_MODEL_NODES:
        raise ModelError(path, f"has {nodes:,} nodes, more than the {MAX_MODEL_NODES:,} a model may have")
    for g in graphs:
        tensors = list(g.initializer) + [a.t for n in g.node for a in n.attribute if a.HasField("t")]
        if any(t.data_location == TensorProto.EXTERNAL for t in tensors):
            raise ModelError(path, "keeps weights in external data files; give one self-contained .onnx file")
    for value in model.graph.input:
        if value.name == input_name:
            dims = value.type.tensor_type.shape.dim
            for dim, size in zip(dims, (1, 3, *input_hw), strict=True):
                dim.Clear()
                dim.dim_value = size
    try:
        onnx.checker.check_model(model)
        inferred = onnx.shape_inference.infer_shapes(model, check_type=True, strict_mode=True, data_prop=True)
    except Exception as exc:  # ONNX's own checker and inference errors for a malformed or inconsistent graph
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:160]
        raise ModelError(path, f"fails ONNX's checks ({first})") from None
    for g in _graphs(inferred.graph):
        known = {v.name: v for v in [*g.input, *g.value_info, *g.output]}
        known_sizes = {t.name: list(t.dims) for t in g.initializer}
        for node in g.node:
            for name in node.output:
                if name:
                    _check_tensor(name, known.get(name), known_sizes.get(name), node.op_type, path, helper)
    return bytes(model.SerializeToString())


def _check_tensor(name: str, value: Any, dims: list[int] | None, op: str, path: Path, helper: Any) -> None:
    shown = name if len(name) <= 60 else name[:57] + "..."
    kind = value.type.tensor_type if value is not None else None
    if dims is None:
        if kind is None or not value.type.HasField("tensor_type") or not kind.HasField("shape") or any(
                not d.HasField("dim_value") for d in kind.shape.dim):
            raise ModelError(path, f"has a tensor whose shape is not static ('{shown}', made by {op}) once its input "
                             "is fixed: a model's memory must be known before it runs")
        dims = [d.dim_value for d in kind.shape.dim]
    elem_type = kind.elem_type if kind is not None else 1
    try:
        itemsize = np.dtype(helper.tensor_dtype_to_np_dtype(elem_type)).itemsize
    except (KeyError, TypeError, ValueError):
        raise ModelError(path, f"has a tensor of an element type bt_grasp cannot size ('{shown}')") from None
    size = math.prod(dims) * itemsize
    if size > MAX_TENSOR_BYTES:
        raise ModelError(path, f"has a tensor of {size:,} bytes ('{shown}', made by {op}, shape {dims}), more than "
                         f"the {MAX_TENSOR_BYTES:,} a model may hold in one")


def first_inference(model: bytes, input_name: str, input_hw: tuple[int, int], path: Path) -> None:
    """Run the model once on a blank picture in a child process under :data:`FIRST_INFERENCE_MEMORY_BYTES` and
    :data:`FIRST_INFERENCE_TIMEOUT_S`; one sentence when it fails. Once per model content and process."""
    digest = hashlib.sha256(model).hexdigest()
    if digest in _checked:
        return
    header = json.dumps({"input": input_name, "hw": list(input_hw)}).encode() + b"\n"
    code = "from bt_grasp.detector.model import first_inference_here; first_inference_here()"
    try:
        proc = subprocess.run([sys.executable, "-c", code], input=header + model, capture_output=True,
                              timeout=FIRST_INFERENCE_TIMEOUT_S, preexec_fn=_child_limits, check=False)
    except subprocess.TimeoutExpired:
        raise ModelError(path, f"did not finish its first inference within {FIRST_INFERENCE_TIMEOUT_S:g} s") from None
    if proc.returncode != 0:
        raise ModelError(path, f"failed its first inference, run apart under a {FIRST_INFERENCE_MEMORY_BYTES >> 20} "
                         f"MiB memory limit (exit {proc.returncode}); a model must run within it")
    _checked.add(digest)


def _child_limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (FIRST_INFERENCE_MEMORY_BYTES, FIRST_INFERENCE_MEMORY_BYTES))


def first_inference_here() -> None:
    """The child's side of :func:`first_inference`: a header line and the model on stdin."""
    ort = _onnxruntime()
    stream = io.BytesIO(sys.stdin.buffer.read())
    header = json.loads(stream.readline())
    height, width = header["hw"]
    session = ort.InferenceSession(stream.read(), sess_options=_session_options(ort, 1),
                                   providers=["CPUExecutionProvider"])
    session.run(None, {header["input"]: np.zeros((1, 3, height, width), dtype=np.float32)})


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
