"""Labels in the Ultralytics OBB format from per-object visible masks, and the files of a dataset.

Pure image and file work (numpy, OpenCV, YAML): the simulator side (``bt_grasp.sim.labelling``) renders the
pictures and the masks; this module turns a mask into an oriented box (``cv2.minAreaRect`` of its pixels) and
writes ``images/``, ``labels/`` (one ``class x1 y1 x2 y2 x3 y3 x4 y4`` line per object, corners normalised to
[0, 1]), ``data.yaml`` and a preview picture of the labels drawn on samples.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml
from numpy.typing import NDArray

from bt_grasp.errors import ConfigError

#: the shipped household catalogue: its object names are classes
CATALOGUE = Path(__file__).resolve().parents[1] / "assets" / "household" / "objects.yaml"
#: the primitive shapes a scene may hold: each is a class
PRIMITIVE_CLASSES = ("box", "cylinder", "sphere")
#: objects with fewer visible pixels than this get no label (fully or mostly hidden)
DEFAULT_MIN_PIXELS = 60


def catalogue_names(path: Path = CATALOGUE) -> tuple[str, ...]:
    """The household catalogue's object names, in the catalogue's order."""
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    return tuple(str(name) for name in data["objects"])


def dataset_classes() -> tuple[str, ...]:
    """Every class a bt_grasp dataset labels, index = class id: the catalogue's objects, then the primitives.
    Fixed whatever scenes a dataset is made from, so datasets (and models) of different scenes agree."""
    return (*catalogue_names(), *PRIMITIVE_CLASSES)


def object_class(shape: str, mesh: str | None, scene: Path, object_name: str) -> str:
    """The class of a scene object: a primitive's shape, or the catalogue name of a household mesh (its file's
    stem). A mesh or URDF outside the catalogue has no class: a one-sentence error naming the scene and object."""
    if shape in PRIMITIVE_CLASSES:
        return shape
    stem = Path(mesh).stem if mesh else ""
    if shape == "mesh" and stem in catalogue_names():
        return stem
    raise ConfigError(scene, f"object '{object_name}' ({shape} {mesh or ''}) is not a household catalogue object "
                             f"nor a primitive, so it has no detector class; classes: {', '.join(dataset_classes())}",
                      f"objects.{object_name}")


@dataclass(frozen=True)
class ObbLabel:
    """One object's oriented box in pixels: 4 corners (4, 2), its class id and visible pixel count."""

    class_id: int
    corners_px: NDArray[np.float64]
    pixels: int


def label_from_mask(mask: NDArray[np.bool_], class_id: int, min_pixels: int) -> ObbLabel | None:
    """``cv2.minAreaRect`` of the mask's pixel centres, grown by half a pixel so the box covers the pixels'
    area; None when fewer than ``min_pixels`` pixels are visible."""
    ys, xs = np.nonzero(mask)
    if len(xs) < min_pixels:
        return None
    points = np.stack([xs, ys], axis=1).astype(np.float32)
    (cx, cy), (w, h), angle = cv2.minAreaRect(points)
    corners = cv2.boxPoints(((cx, cy), (w + 1.0, h + 1.0), angle)).astype(np.float64)
    return ObbLabel(class_id, corners, len(xs))


def label_lines(labels: Sequence[ObbLabel], width_px: int, height_px: int) -> str:
    """The label file's text: ``class x1 y1 ... x4 y4`` per object, corners normalised and clipped to [0, 1]."""
    lines = []
    for label in labels:
        norm = label.corners_px / np.array([width_px, height_px], dtype=np.float64)
        norm = np.clip(norm, 0.0, 1.0)
        lines.append(" ".join([str(label.class_id), *(f"{v:.6f}" for v in norm.reshape(-1))]))
    return "".join(line + "\n" for line in lines)


def read_label_file(path: Path, width_px: int, height_px: int) -> list[tuple[int, NDArray[np.float64]]]:
    """A label file back as (class id, corners in pixels (4, 2))."""
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        parts = line.split()
        corners = np.array([float(v) for v in parts[1:]], dtype=np.float64).reshape(4, 2)
        out.append((int(parts[0]), corners * np.array([width_px, height_px], dtype=np.float64)))
    return out


def data_yaml(names: Sequence[str]) -> str:
    """Ultralytics' dataset file: every image for training and validation (make a held-out set with another
    seed), the class names by index."""
    doc = {"path": ".", "train": "images", "val": "images", "names": dict(enumerate(names))}
    return yaml.safe_dump(doc, sort_keys=False)


def draw_labels(rgb: NDArray[np.uint8], labels: Sequence[ObbLabel], names: Sequence[str]) -> NDArray[np.uint8]:
    """The image with each label's box and class name drawn (BGR for cv2.imwrite)."""
    out = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
    for label in labels:
        hue = (label.class_id * 47) % 180
        hsv = np.array([[[hue, 220, 255]]], dtype=np.uint8)
        color = [int(v) for v in cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0]]
        poly = np.round(label.corners_px).astype(np.int32)
        cv2.polylines(out, [poly], True, color, 2, lineType=cv2.LINE_AA)
        x, y = poly[:, 0].min(), max(int(poly[:, 1].min()) - 4, 10)
        cv2.putText(out, names[label.class_id], (int(x), y), cv2.FONT_HERSHEY_SIMPLEX, 0.45, color, 1, cv2.LINE_AA)
    return np.asarray(out, dtype=np.uint8)


def preview_grid(tiles: Sequence[NDArray[np.uint8]], columns: int = 2) -> NDArray[np.uint8]:
    """Up to ``columns`` x n tiles of equal size side by side (a black tile fills the last row)."""
    h, w = tiles[0].shape[:2]
    rows = -(-len(tiles) // columns)
    grid = np.zeros((rows * h, columns * w, 3), dtype=np.uint8)
    for k, tile in enumerate(tiles):
        r, c = divmod(k, columns)
        grid[r * h : (r + 1) * h, c * w : (c + 1) * w] = cv2.resize(tile, (w, h)) if tile.shape[:2] != (h, w) else tile
    return grid
