"""Touching objects: one DBSCAN cluster cut into the objects its top view shows, where the geometry allows.

Two objects that touch form one cluster (DBSCAN joins points closer than its radius). Seen from above, the
cluster is a height map on a 4 mm grid of the table plane (each cell holds the highest point above it). Two
neighbouring cells belong to one surface unless their heights differ by a step (``STEP_M``): the parts left
after cutting every step are candidate objects. A part is an object only when it is solid (it survives an
erosion of ``ERODE_CELLS`` cells: the thin rim of steep sides around a sphere or a lying can is not) and
holds enough points; everything else (rims, specks) joins the nearest solid part.

Where the cut is not trusted, the cluster stays one, with a reason in ``Split.note``:

* a solid part with no point near the table stands on another (stacked objects, or one hidden behind another
  from the camera): its footprint cannot be told from the other's;
* objects of the same height pressed side to side leave no step at all: nothing to cut, and nothing in the
  geometry says there are two (no note: the cluster is reported as what it looks like, one object).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from bt_grasp.perception.cloud import PixelCloud
from bt_grasp.perception.segment import Plane

CELL_M = 0.004  # height-map cell side
STEP_M = 0.015  # neighbouring cells whose heights differ this much lie on two surfaces
ERODE_CELLS = 2  # a solid part survives this many 3 x 3 erosions (it is at least ~2 cm across)
NEAR_TABLE_M = 0.015  # an object standing on the table shows a point this low (its side facing the camera)


@dataclass(frozen=True)
class Split:
    """The objects one cluster was cut into (itself alone when not cut) and why it was not cut, if doubtful."""

    parts: tuple[PixelCloud, ...]
    note: str = ""


def split_touching(obj: PixelCloud, plane: Plane, min_points: int) -> Split:
    """Cut one cluster into the objects its height map shows (see the module docstring)."""
    pts = obj.points
    if len(pts) < 2 * min_points:
        return Split((obj,))
    h = plane.height(pts)
    origin, e1, e2 = plane.basis()
    rel = pts - origin
    iu = np.floor(rel @ e1 / CELL_M).astype(np.int64)
    iv = np.floor(rel @ e2 / CELL_M).astype(np.int64)
    iu -= iu.min()
    iv -= iv.min()
    width, rows = int(iu.max()) + 1, int(iv.max()) + 1
    cell = iv * width + iu
    top = np.full(width * rows, -np.inf)
    np.maximum.at(top, cell, h)
    grid = top.reshape(rows, width)
    occupied = np.isfinite(grid)
    index = np.full(grid.shape, -1, dtype=np.int64)
    index[occupied] = np.arange(int(occupied.sum()))
    a_list, b_list = [], []
    for da, db in (((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
                   ((slice(None, -1), slice(None)), (slice(1, None), slice(None)))):
        same = occupied[da] & occupied[db]
        with np.errstate(invalid="ignore"):
            same &= np.abs(grid[da] - grid[db]) < STEP_M
        a_list.append(index[da][same])
        b_list.append(index[db][same])
    a, b = np.concatenate(a_list), np.concatenate(b_list)
    n = int(occupied.sum())
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    n_parts, part_of_cell = connected_components(graph, directed=False)
    if n_parts < 2:
        return Split((obj,))
    part_grid = np.full(grid.shape, -1, dtype=np.int64)
    part_grid[occupied] = part_of_cell
    point_part = part_grid[iv, iu]
    counts = np.bincount(point_part, minlength=n_parts)
    solid = []
    for k in range(n_parts):
        if counts[k] < min_points:
            continue
        if ndimage.binary_erosion(part_grid == k, iterations=ERODE_CELLS).any():
            solid.append(k)
    if len(solid) < 2:
        return Split((obj,))
    lowest = {k: float(h[point_part == k].min()) for k in solid}
    floating = [k for k in solid if lowest[k] > NEAR_TABLE_M]
    if floating:
        k = max(floating, key=lambda j: lowest[j])
        return Split((obj,), f"one cluster of {len(solid)} surfaces at different heights: the one whose lowest "
                             f"point is {lowest[k] * 1e3:.0f} mm above the table stands on (or behind) another, "
                             "so their footprints cannot be told apart")
    owner = np.full(n_parts, -1, dtype=np.int64)
    owner[solid] = np.arange(len(solid))
    point_owner = owner[point_part]
    loose = point_owner < 0
    if loose.any():
        uv = np.stack([iu, iv], axis=1).astype(float)
        tree = cKDTree(uv[~loose])
        _, nearest = tree.query(uv[loose], k=1)
        point_owner[loose] = point_owner[~loose][nearest]
    parts = [obj.select(point_owner == j) for j in range(len(solid))]
    parts.sort(key=lambda p: (-len(p), tuple(p.points.mean(axis=0))))
    return Split(tuple(parts))
