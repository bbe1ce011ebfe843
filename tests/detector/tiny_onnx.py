"""Tiny ONNX models made by the tests with the ``onnx`` helper API: their one output is a crafted tensor (the
export layout ``[1, 4 + nc + 1, anchors]`` or a deliberately wrong one), plus 0 x the image's maximum so the graph
does read its input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import onnx
from numpy.typing import NDArray
from onnx import TensorProto, helper, numpy_helper


def write_model(path: Path, output: NDArray[np.float32], *, input_shape: tuple[object, ...] = (1, 3, 320, 320),
                names: dict[int, str] | None = None, imgsz: object = None, output_shape: list[object] | None = None,
                outputs: int = 1) -> Path:
    """Write a model whose output is ``output`` (any shape) to ``path``; ``names``/``imgsz`` go into the metadata
    as Ultralytics writes them (Python literals as strings)."""
    const = numpy_helper.from_array(np.asarray(output, dtype=np.float32), name="crafted")
    nodes = [
        helper.make_node("ReduceMax", ["images"], ["peak"], keepdims=0),
        helper.make_node("Constant", [], ["zero"], value=numpy_helper.from_array(np.array(0.0, np.float32))),
        helper.make_node("Mul", ["peak", "zero"], ["nothing"]),
        helper.make_node("Constant", [], ["table"], value=const),
        helper.make_node("Add", ["table", "nothing"], ["output0"]),
    ]
    graph_outputs = [helper.make_tensor_value_info("output0", TensorProto.FLOAT, output_shape or list(output.shape))]
    for k in range(1, outputs):
        nodes.append(helper.make_node("Identity", ["output0"], [f"extra{k}"]))
        graph_outputs.append(helper.make_tensor_value_info(f"extra{k}", TensorProto.FLOAT, list(output.shape)))
    graph = helper.make_graph(
        nodes, "crafted_obb",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, list(input_shape))],
        graph_outputs,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)], producer_name="bt_grasp tests")
    model.ir_version = 9
    metadata = {}
    if names is not None:
        metadata["names"] = str(names)
    if imgsz is not None:
        metadata["imgsz"] = str(imgsz)
    metadata["task"] = "obb"
    helper.set_model_props(model, metadata)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


def raw_output(rows: list[tuple[float, float, float, float, float, int, float]], nc: int,
               anchors: int = 16) -> NDArray[np.float32]:
    """``[1, 4 + nc + 1, anchors]`` with one anchor per row (cx, cy, w, h in input pixels, angle, class, score),
    the other classes' scores 0.01 and the remaining anchors all-zero (score 0: never a candidate)."""
    out = np.zeros((1, 4 + nc + 1, anchors), dtype=np.float32)
    for a, (cx, cy, w, h, angle, cls, score) in enumerate(rows):
        out[0, 0:4, a] = (cx, cy, w, h)
        out[0, 4 : 4 + nc, a] = 0.01
        out[0, 4 + cls, a] = score
        out[0, -1, a] = angle
    return out
