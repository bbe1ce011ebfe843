"""Free placement in a tray or bin: where on its floor a held object can be set down, clear of the walls and of
what was set down there before (issue 28: five household objects into one bin, in whatever order they come).

Everything here is in the container's frame: origin at the middle of its floor's top, x along its first inner
side, z up. An object at rest is an upright prism (its footprint rectangle, from the floor to its height); the
open gripper at the release is a few boxes (palm, finger pads) fixed to the object by the grasp. A spot is a
position and a yaw where

- the object's footprint, grown by ``margin_m`` on every side, lies clear of every object set down before,
  each grown the same way, and ``wall_margin_m`` inside the walls: what perception does not see of an object
  (the part within its height threshold of the table: a wedge's thin end, a banana's tips, a can's body under
  its narrower lid) is up to ~8 mm beyond its footprint, and an object set down a few mm off where it was
  meant to go (it shifted in the fingers) leans on a neighbour harmlessly but tilts with an end on a wall;
- every box of the open gripper is ``clearance_m`` clear of the walls and of those objects wherever it comes
  lower than their tops: it comes down vertically, so whatever stands under it on its way down is in the way
  (and it leaves upwards: after a side grasp Place rises first where backing off low is blocked). Nothing of
  the gripper may come below the walls' top outside them either (it would pass a wall).

Spots are ranked by how much of the release's envelope (the box round the grown footprint and the gripper's
parts that come lower than the walls' top: the open pads, a side grasp's palm and wrist) lies against a wall or
an object already set down: the touching-perimeter rule of two-dimensional bin packing, on what the release
takes of the floor (objects packed against each other and the walls leave the rest of the floor in one piece
for the next; measured on the footprint alone, the pads kept every object off its neighbours by more than
they need and scattered five objects over the middle of the bin). Then by how far they are from
``far_from_xy`` (the robot's base: the container is filled from its far side, so the arm does not reach over
what it set down), then by position. A rectangle lies along or across the container (its sides parallel to
the walls: no floor is wasted in slivers), each also half a turn round (the gripper is then elsewhere); a
round footprint is tried every 30 degrees. The order depends on the arguments alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, convex_hull_xy, make_T, rot_z

#: the step of the grid of positions tried besides those against a wall or an object, m
GRID_STEP_M = 0.01
#: the turns tried for a round footprint, degrees apart
ROUND_STEP_DEG = 30.0
#: walls are modelled this thick, outward: no part of the gripper below their top outside the container
_WALL_DEPTH_M = 0.5
_EPS = 1e-9


@dataclass(frozen=True)
class Floor:
    """The free floor inside the walls: half its sides, and the walls' height above it."""

    half_x_m: float
    half_y_m: float
    wall_height_m: float


@dataclass(frozen=True)
class Resting:
    """Something set down on the floor before, as it was put there (its perceived footprint and height)."""

    centre_xy_m: tuple[float, float]
    yaw_rad: float
    size_xy_m: tuple[float, float]  # length, width
    height_m: float


@dataclass(frozen=True)
class ToolPart:
    """A box of the open gripper at the release, fixed to the held object: its full size and its pose in the
    object's resting frame (origin at the middle of its footprint on the floor, x along its length, z up)."""

    size_m: tuple[float, float, float]
    T_object_part: Mat4


@dataclass(frozen=True)
class HeldShape:
    """The held object as perceived (footprint, height, round or not) and the gripper around it."""

    length_m: float
    width_m: float
    height_m: float
    round_footprint: bool
    parts: tuple[ToolPart, ...] = ()


@dataclass(frozen=True)
class Spot:
    """Where the held object's footprint centre goes and its yaw (container frame), and how much of its grown
    footprint touches a wall or an object set down before (m of perimeter)."""

    x_m: float
    y_m: float
    yaw_rad: float
    contact_m: float


@dataclass(frozen=True)
class _Block:
    """An axis-aligned obstacle rectangle [x0, x1] x [y0, y1] standing from the floor up to ``top_m``."""

    x0: float
    x1: float
    y0: float
    y1: float
    top_m: float


def _block(rest: Resting, grow: float) -> _Block:
    """The box round a resting object's turned footprint, grown, up to its top."""
    c, s = abs(math.cos(rest.yaw_rad)), abs(math.sin(rest.yaw_rad))
    (x, y), (length, width) = rest.centre_xy_m, rest.size_xy_m
    hx = (c * length + s * width) / 2 + grow
    hy = (s * length + c * width) / 2 + grow
    return _Block(x - hx, x + hx, y - hy, y + hy, rest.height_m)


def obstacles(floor: Floor, resting: Sequence[Resting], margin_m: float) -> list[_Block]:
    """The walls (thick, outward) and what rests on the floor (its box round its turned footprint, grown)."""
    hx, hy, h, d = floor.half_x_m, floor.half_y_m, floor.wall_height_m, _WALL_DEPTH_M
    walls = [_Block(-hx - d, -hx, -hy - d, hy + d, h), _Block(hx, hx + d, -hy - d, hy + d, h),
             _Block(-hx - d, hx + d, -hy - d, -hy, h), _Block(-hx - d, hx + d, hy, hy + d, h)]
    return walls + [_block(r, margin_m) for r in resting]


def _overlaps(poly: NDArray[np.float64], block: _Block) -> bool:
    """Whether a convex polygon (k, 2) and a rectangle overlap with positive area (touching does not count)."""
    if (poly[:, 0].max() <= block.x0 + _EPS or poly[:, 0].min() >= block.x1 - _EPS
            or poly[:, 1].max() <= block.y0 + _EPS or poly[:, 1].min() >= block.y1 - _EPS):
        return False
    rect = np.array([[block.x0, block.y0], [block.x1, block.y0], [block.x1, block.y1], [block.x0, block.y1]])
    edges = np.roll(poly, -1, axis=0) - poly
    for nx, ny in np.stack([-edges[:, 1], edges[:, 0]], axis=1):
        a, b = poly @ (nx, ny), rect @ (nx, ny)
        if a.max() <= b.min() + _EPS or b.max() <= a.min() + _EPS:
            return False
    return True


def _shadow(part: ToolPart, T_container_object: Mat4, grow: float) -> tuple[NDArray[np.float64], float]:
    """The part's outline seen from above (the hull of its corners, grown) and its lowest point."""
    half = np.asarray(part.size_m) / 2 + grow
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    T = np.asarray(T_container_object) @ np.asarray(part.T_object_part)
    pts = corners @ T[:3, :3].T + T[:3, 3]
    return convex_hull_xy(pts[:, :2], decimals=12), float(pts[:, 2].min())


def _contact(x0: NDArray[np.float64], x1: NDArray[np.float64], y0: NDArray[np.float64], y1: NDArray[np.float64],
             blocks: Sequence[_Block]) -> NDArray[np.float64]:
    """How much of each rectangle's perimeter lies against the blocks' sides (walls included)."""
    total = np.zeros_like(x0)
    for b in blocks:
        along_y = np.clip(np.minimum(y1, b.y1) - np.maximum(y0, b.y0), 0.0, None)
        along_x = np.clip(np.minimum(x1, b.x1) - np.maximum(x0, b.x0), 0.0, None)
        total += along_y * ((np.abs(x0 - b.x1) < 1e-7) | (np.abs(x1 - b.x0) < 1e-7))
        total += along_x * ((np.abs(y0 - b.y1) < 1e-7) | (np.abs(y1 - b.y0) < 1e-7))
    return total


def _yaws(held: HeldShape) -> tuple[float, ...]:
    """The yaws tried: a rectangle along the container and across it, each also half a turn round; a round
    footprint every 30 degrees."""
    if held.round_footprint:
        return tuple(math.radians(ROUND_STEP_DEG * k) for k in range(round(360.0 / ROUND_STEP_DEG)))
    return (0.0, math.pi, math.pi / 2, -math.pi / 2)


def _envelope(held: HeldShape, yaw: float, half: tuple[float, float], clearance_m: float, low_m: float
              ) -> tuple[float, float, float, float]:
    """The box round the grown footprint and the gripper's parts that come lower than ``low_m`` (the walls'
    top: the pads, a side grasp's palm), relative to the footprint's centre: what the release takes of the
    floor."""
    x0, x1, y0, y1 = -half[0], half[0], -half[1], half[1]
    T = make_T(rot_z(yaw), [0.0, 0.0, 0.0])
    for part in held.parts:
        outline, lowest = _shadow(part, T, clearance_m)
        if lowest < low_m:
            x0, x1 = min(x0, float(outline[:, 0].min())), max(x1, float(outline[:, 0].max()))
            y0, y1 = min(y0, float(outline[:, 1].min())), max(y1, float(outline[:, 1].max()))
    return x0, x1, y0, y1


def _axis(lo: float, hi: float, half: float, env: tuple[float, float], edges: Sequence[tuple[float, float]],
          step: float) -> NDArray[np.float64]:
    """Centre coordinates along one axis where the footprint fits between the walls: the footprint or the
    release's envelope (``env``: its low and high offsets) against a wall or an object's side, and a grid."""
    if hi - lo < 2 * half - _EPS:
        return np.zeros(0)
    out = {lo + half, hi - half, lo - env[0], hi - env[1]}
    for e0, e1 in edges:
        out.update((e1 + half, e0 - half, e1 - env[0], e0 - env[1]))
    n = math.floor((hi - lo - 2 * half) / step + _EPS)
    out.update(lo + half + k * step for k in range(n + 1))
    return np.array(sorted(c for c in out if lo + half - _EPS <= c <= hi - half + _EPS))


def free_spots(floor: Floor, resting: Sequence[Resting], held: HeldShape, *, margin_m: float = 0.01,
               wall_margin_m: float = 0.0, clearance_m: float = 0.005, far_from_xy: tuple[float, float] = (0.0, 0.0),
               limit: int = 0, step_m: float = GRID_STEP_M) -> list[Spot]:
    """The spots where the held object can be set down, best first (see the module's docstring); at most
    ``limit`` of them (0: all). The footprint keeps ``wall_margin_m`` from the walls when that is more than
    ``margin_m`` (the gripper's parts keep only their clearance)."""
    blocks = obstacles(floor, resting, margin_m)
    inset = max(0.0, wall_margin_m - margin_m)
    hx, hy = floor.half_x_m - inset, floor.half_y_m - inset
    fitting = obstacles(Floor(hx, hy, floor.wall_height_m), resting, margin_m)  # what the footprint packs against
    placed = blocks[4:]
    size = (held.length_m, held.width_m) if not held.round_footprint else (max(held.length_m, held.width_m),) * 2
    keys, rows = [], []
    for k, yaw in enumerate(_yaws(held)):
        across = abs(math.sin(yaw)) > 0.5 and not held.round_footprint
        a = (size[1] if across else size[0]) / 2 + margin_m
        b = (size[0] if across else size[1]) / 2 + margin_m
        ex0, ex1, ey0, ey1 = _envelope(held, yaw, (a, b), clearance_m, floor.wall_height_m)
        xs = _axis(-hx, hx, a, (ex0, ex1), [(p.x0, p.x1) for p in placed], step_m)
        ys = _axis(-hy, hy, b, (ey0, ey1), [(p.y0, p.y1) for p in placed], step_m)
        X, Y = (v.ravel() for v in np.meshgrid(xs, ys, indexing="ij"))
        free = np.ones(X.shape, dtype=bool)
        for p in placed:
            free &= ~((X - a < p.x1 - _EPS) & (X + a > p.x0 + _EPS) & (Y - b < p.y1 - _EPS) & (Y + b > p.y0 + _EPS))
        X, Y = X[free], Y[free]
        contact = _contact(X + ex0, X + ex1, Y + ey0, Y + ey1, fitting)
        far = np.hypot(X - far_from_xy[0], Y - far_from_xy[1])
        keys.append(np.stack([-np.round(contact, 6), -np.round(far, 6), np.round(X, 6), np.round(Y, 6),
                              np.full(X.shape, float(k))]))
        rows.append(np.stack([X, Y, np.full(X.shape, yaw), contact]))
    if not keys:
        return []
    key, row = np.concatenate(keys, axis=1), np.concatenate(rows, axis=1)
    out: list[Spot] = []
    for i in np.lexsort(key[::-1]):
        x, y, yaw, touching = (float(v) for v in row[:, i])
        if _gripper_clear(held, x, y, yaw, blocks, clearance_m):
            out.append(Spot(x, y, yaw, touching))
            if limit and len(out) >= limit:
                break
    return out


def _gripper_clear(held: HeldShape, x: float, y: float, yaw: float, blocks: Sequence[_Block],
                   clearance_m: float) -> bool:
    """Whether every part of the open gripper, with the object at (x, y, yaw), stays clear on its way down."""
    T = make_T(rot_z(yaw), [x, y, 0.0])
    for part in held.parts:
        outline, lowest = _shadow(part, T, clearance_m)
        for block in blocks:
            if lowest < block.top_m and _overlaps(outline, block):
                return False
    return True
