"""A RealSense D435-like noise model for rendered depth and colour (numpy only, seeded).

Depth: stereo error grows with the square of the distance (RMS = z^2 * subpixel / (focal * baseline)),
readings are quantised, pixels on the far side of a depth discontinuity drop out (the stereo shadow),
and anything closer than the minimum or beyond the maximum range reads 0 (invalid).
Colour: additive Gaussian noise in 8-bit levels.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bt_grasp.scene.format import DepthNoise


def depth_rms_m(z_m: NDArray[np.floating] | float, noise: DepthNoise) -> NDArray[np.float64]:
    """Standard deviation of the depth error at distance z."""
    return np.asarray(z_m, dtype=np.float64) ** 2 * noise.subpixel / (noise.focal_px * noise.baseline_m)


def _edge_far_side(depth_m: NDArray[np.float32], jump_m: float) -> NDArray[np.bool_]:
    """Pixels that have a neighbour (4-connected) nearer by more than jump_m: the far side of an edge."""
    far = np.zeros(depth_m.shape, dtype=bool)
    d = depth_m
    for axis in (0, 1):
        diff = np.diff(d, axis=axis)
        # diff[i] = d[i+1] - d[i]; d[i+1] far side when diff > jump, d[i] far side when diff < -jump
        if axis == 0:
            far[1:, :] |= diff > jump_m
            far[:-1, :] |= diff < -jump_m
        else:
            far[:, 1:] |= diff > jump_m
            far[:, :-1] |= diff < -jump_m
    return far


def apply_depth_noise(depth_m: NDArray[np.float32], noise: DepthNoise, rng: np.random.Generator) -> NDArray[np.float32]:
    """Noisy depth (0 = invalid) from true depth (0 = nothing rendered)."""
    depth = depth_m.astype(np.float32, copy=True)
    valid = depth > 0
    if not noise.enabled:
        return depth
    edges = _edge_far_side(np.where(valid, depth, np.float32(1e3)), noise.edge_jump_m)
    dropout = edges & (rng.random(depth.shape) < noise.edge_dropout)
    sigma = depth_rms_m(depth, noise)
    depth = depth + rng.standard_normal(depth.shape).astype(np.float32) * np.asarray(sigma, dtype=np.float32)
    if noise.quantum_m > 0:
        depth = np.round(depth / noise.quantum_m) * np.float32(noise.quantum_m)
    out_of_range = (depth < noise.min_range_m) | (depth > noise.max_range_m)
    depth[~valid | dropout | out_of_range] = 0.0
    return depth.astype(np.float32)


def apply_color_noise(color: NDArray[np.uint8], noise: DepthNoise, rng: np.random.Generator) -> NDArray[np.uint8]:
    if not noise.enabled or noise.color_sigma <= 0:
        return color
    noisy = color.astype(np.float32) + rng.standard_normal(color.shape).astype(np.float32) * noise.color_sigma
    return np.clip(np.round(noisy), 0, 255).astype(np.uint8)
