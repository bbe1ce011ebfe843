"""Which detector a perceiving leaf uses, and where the shipped model lives (no numpy, OpenCV or onnxruntime:
tree files are validated with this module alone)."""

from __future__ import annotations

import enum
from pathlib import Path


class DetectorKind(enum.StrEnum):
    """What finds the objects in a frame (the ``detector`` port of ``Perceive`` and ``PerceiveAll``)."""

    GEOMETRIC = "geometric"  # the point-cloud pipeline alone: objects by geometry, named by colour
    LEARNED = "learned"  # a YOLO-OBB network's oriented boxes by class, joined with the point-cloud pipeline


#: the household model shipped with bt_grasp (what an empty ``model`` port means)
SHIPPED_MODEL = Path(__file__).resolve().parents[1] / "assets" / "detector" / "household_obb.onnx"


def parse_detector(text: str) -> DetectorKind | None:
    """The kind a port's text names ('' = geometric), or None when it names none."""
    try:
        return DetectorKind(text.strip() or DetectorKind.GEOMETRIC.value)
    except ValueError:
        return None


def model_path(text: str, tree_file: str | Path | None) -> Path:
    """The model a ``model`` port names: '' is the shipped model; a relative path written in a tree file is
    relative to that file's folder (as an ``<include>`` is); one from the blackboard (``tree_file`` None) is
    relative to the working directory."""
    if not text.strip():
        return SHIPPED_MODEL
    path = Path(text.strip()).expanduser()
    if path.is_absolute() or tree_file is None or not str(tree_file) or str(tree_file).startswith("<"):
        return path
    return Path(tree_file).parent / path
