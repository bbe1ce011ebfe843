"""A randomised table-top texture for the detector's dataset pictures (`bt-grasp detector dataset`): a tool, not
the pipeline.

The table of every scene is one flat colour; a network trained only on flat tables may take a grain, a tile
joint or a stain for an object, or miss an object on a busy top. ``texture_image`` draws one of a few procedural
surfaces around the picture's table colour from a seeded generator (numpy and OpenCV only, so the same seed draws
the same texels): ``wood`` (wavy grain along a random direction), ``mottled`` (smooth noise of several scales),
``tiles`` (square tiles of random size and tint with grout joints), ``speckle`` (a granite-like stone) or
``plain`` (the scene's own flat table). ``add_table_top`` lays the texture on the table as a render-only quad
0.3 mm above the top (no physics, no depth change a caller could measure); the segmentation ignores it (it is no
object).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np
import sapien
from numpy.typing import NDArray

#: the surfaces drawn, in the order their names are recorded; "plain" adds nothing
TEXTURE_KINDS = ("plain", "wood", "mottled", "tiles", "speckle")
TEXTURE_PX = 1024
#: the quad's height above the table top, m: above it (no z-fighting), far below anything a label measures
LIFT_M = 0.0003


def _smooth_noise(rng: np.random.Generator, size: int, cells: int) -> NDArray[np.float32]:
    """Value noise in [-1, 1]: a ``cells`` x ``cells`` grid of random values, resized bicubically to ``size``."""
    grid = rng.uniform(-1.0, 1.0, (cells, cells)).astype(np.float32)
    return np.asarray(cv2.resize(grid, (size, size), interpolation=cv2.INTER_CUBIC), dtype=np.float32)


def _octaves(rng: np.random.Generator, size: int, scales: Sequence[int]) -> NDArray[np.float32]:
    total = np.zeros((size, size), np.float32)
    weight = 1.0
    for cells in scales:
        total += weight * _smooth_noise(rng, size, cells)
        weight *= 0.5
    return np.asarray(total / max(float(np.abs(total).max()), 1e-6), dtype=np.float32)


def _wood(rng: np.random.Generator, size: int) -> NDArray[np.float32]:
    theta = rng.uniform(0.0, math.pi)
    v, u = np.mgrid[0:size, 0:size].astype(np.float32) / size
    along = u * math.cos(theta) + v * math.sin(theta)
    warp = _octaves(rng, size, (4, 9)) * rng.uniform(0.02, 0.08)
    rings = np.sin(2 * math.pi * (along + warp) * rng.uniform(15.0, 60.0))
    return np.asarray(0.6 * rings + 0.4 * _octaves(rng, size, (24, 64)), dtype=np.float32)


def _tiles(rng: np.random.Generator, size: int) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Each tile's tint offset in [-1, 1] and the grout mask (1 in the joints)."""
    n = int(rng.integers(4, 16))
    tint = cv2.resize(rng.uniform(-1.0, 1.0, (n, n)).astype(np.float32), (size, size),
                      interpolation=cv2.INTER_NEAREST)
    period = size / n
    joint = max(1.0, period * rng.uniform(0.02, 0.06))
    v, u = np.mgrid[0:size, 0:size].astype(np.float32)
    grout = ((u % period) < joint) | ((v % period) < joint)
    return np.asarray(tint, dtype=np.float32), grout.astype(np.float32)


def texture_image(kind: str, base_rgb: Sequence[float], rng: np.random.Generator,
                  size: int = TEXTURE_PX) -> NDArray[np.uint8] | None:
    """An RGBA texture (size, size, 4) of ``kind`` around ``base_rgb`` (linear 0-1), or None for ``plain``."""
    if kind not in TEXTURE_KINDS:
        raise ValueError(f"unknown table texture '{kind}' (one of {', '.join(TEXTURE_KINDS)})")
    if kind == "plain":
        return None
    base = np.asarray(base_rgb, dtype=np.float32).reshape(1, 1, 3)
    strength = float(rng.uniform(0.08, 0.25))
    if kind == "wood":
        pattern = _wood(rng, size)[..., None]
        second = np.asarray(rng.uniform(-0.15, 0.15, 3), dtype=np.float32).reshape(1, 1, 3)
        rgb = base * (1.0 + strength * pattern) + second * np.clip(pattern, 0, 1) * strength
    elif kind == "mottled":
        pattern = _octaves(rng, size, (3, 8, 20, 60))[..., None]
        rgb = base * (1.0 + strength * 1.5 * pattern)
    elif kind == "tiles":
        tint, grout = _tiles(rng, size)
        grout_rgb = np.asarray(rng.uniform(0.2, 0.9, 3), dtype=np.float32).reshape(1, 1, 3)
        rgb = base * (1.0 + strength * tint[..., None]) * (1.0 - grout[..., None]) + grout_rgb * grout[..., None]
    else:  # speckle
        fine = rng.uniform(-1.0, 1.0, (size, size)).astype(np.float32)
        dots = (rng.random((size, size)) < rng.uniform(0.01, 0.06)).astype(np.float32)
        dots = cv2.GaussianBlur(dots, (3, 3), 0.7) * rng.choice([-1.0, 1.0])
        pattern = 0.3 * cv2.GaussianBlur(fine, (3, 3), 0.8) + 1.5 * dots + 0.3 * _octaves(rng, size, (6, 16))
        pattern = pattern / max(float(pattern.std()), 1e-6)  # grains of stone: visible whatever the draw
        rgb = base * (1.0 + 0.6 * strength * pattern[..., None])
    out = np.clip(rgb, 0.0, 1.0)
    rgba = np.concatenate([out, np.ones((size, size, 1), np.float32)], axis=2)
    return np.ascontiguousarray(np.round(rgba * 255.0), dtype=np.uint8)


def add_table_top(scene: sapien.Scene, rgba: NDArray[np.uint8], center_xy_m: Sequence[float],
                  size_xy_m: Sequence[float], repeat_m: float) -> None:
    """Lay ``rgba`` on the table top as a render-only quad (one copy of the texture every ``repeat_m``)."""
    texture = sapien.render.RenderTexture2D(np.ascontiguousarray(rgba), "R8G8B8A8Unorm", 6, "linear", "repeat")
    material = sapien.render.RenderMaterial(base_color=[1.0, 1.0, 1.0, 1.0], roughness=0.9, metallic=0.0)
    material.base_color_texture = texture
    cx, cy = float(center_xy_m[0]), float(center_xy_m[1])
    hx, hy = float(size_xy_m[0]) / 2, float(size_xy_m[1]) / 2
    vertices = np.array([[cx - hx, cy - hy, LIFT_M], [cx + hx, cy - hy, LIFT_M], [cx + hx, cy + hy, LIFT_M],
                         [cx - hx, cy + hy, LIFT_M]], dtype=np.float32)
    triangles = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)  # right-hand normals along +z: seen from above
    normals = np.tile(np.array([[0.0, 0.0, 1.0]], dtype=np.float32), (4, 1))
    su, sv = 2 * hx / repeat_m, 2 * hy / repeat_m
    uvs = np.array([[0, 0], [su, 0], [su, sv], [0, sv]], dtype=np.float32)
    shape = sapien.render.RenderShapeTriangleMesh(vertices, triangles, normals, uvs, material)
    body = sapien.render.RenderBodyComponent()
    body.attach(shape)
    entity = sapien.Entity()
    entity.set_name("table_texture")
    entity.add_component(body)
    scene.add_entity(entity)
