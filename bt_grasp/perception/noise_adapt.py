"""Adapting perception to the depth noise it measures in the frame itself.

A stereo camera's depth error grows with the square of the distance: sigma(z) = k * z^2, with k set by the
sensor (baseline, focal length, subpixel accuracy) and by the surface (dark, shiny and textureless surfaces
match worse). Thresholds tuned at one k (the plane fit's inlier distance, the height above the table at
which a point belongs to an object, the top-face band) break when k grows: at 3x the default error every
table point scatters above the 8 mm height cut-off and the objects drown in it.

So perception measures k in each frame and adapts in two principled steps:

1. **Measure** (:func:`estimate_noise_coefficient`): on a smooth surface the second difference of depth
   along a row, d[i-1] - 2 d[i] + d[i+1], is pure noise (the surface's own curvature is far below the
   noise) with variance 6 sigma^2 for independent pixel errors. Its median absolute value over all valid
   pixels, normalised by z^2, is a robust estimate of k (edges and dropouts are a minority the median ignores).
2. **Denoise to the tuned level** (:func:`denoise_depth`): when the measured error at the working distance is
   above the level the fixed thresholds were tuned at (``NoiseSettings.tuned_sigma_m``), average each pixel
   with the neighbours of a (2r+1)^2 window that lie within a few sigma of the window's median (an
   edge-preserving mean, as the D435's own spatial filter does), r chosen so that sigma / sqrt(n) falls back to
   the tuned level. At or below the tuned level nothing changes, so today's accuracy stays what it was.
3. **Thresholds from the residual spread** (:func:`adapt_segmentation`): after the denoising, the plane fit's
   inlier distance, the height cut-off and the top-face band become max(tuned value, c * sigma_height) where
   sigma_height is the spread (1.4826 * MAD) of the table points' heights about the fitted plane, and the
   DBSCAN radius grows with the measured spacing of the off-plane points.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from bt_grasp.perception.config import NoiseSettings, SegmentationSettings
from bt_grasp.perception.results import NoiseEstimate

#: 1.4826 * MAD estimates a normal distribution's standard deviation
_MAD_TO_SIGMA = 1.4826
#: the second difference of three independent errors has standard deviation sqrt(6) sigma
_SECOND_DIFF_GAIN = float(np.sqrt(6.0))


def estimate_noise_coefficient(depth_m: NDArray[np.float32], valid: NDArray[np.bool_]) -> float:
    """k in sigma(z) = k z^2, from the second differences of depth along rows and columns (robust)."""
    rows, cols = np.flatnonzero(valid.any(axis=1)), np.flatnonzero(valid.any(axis=0))
    if rows.size == 0:
        return 0.0
    # only the rectangle holding the valid pixels has samples (three valid pixels in a row or column); the
    # median does not depend on their order
    box = np.s_[int(rows[0]):int(rows[-1]) + 1, int(cols[0]):int(cols[-1]) + 1]
    d, valid = depth_m[box].astype(np.float64), valid[box]
    samples = []
    for axis in (0, 1):
        a = np.moveaxis(d, axis, 0)
        m = np.moveaxis(valid, axis, 0)
        second = a[:-2] - 2.0 * a[1:-1] + a[2:]
        ok = m[:-2] & m[1:-1] & m[2:]
        z = a[1:-1][ok]
        samples.append(np.abs(second[ok]) / np.maximum(z * z, 1e-6))
    s = np.concatenate(samples)
    if s.size < 100:
        return 0.0
    return float(_MAD_TO_SIGMA * np.median(s, overwrite_input=True) / _SECOND_DIFF_GAIN)  # s is ours to reorder


def filter_radius_for(sigma_m: float, settings: NoiseSettings) -> int:
    """Smallest window radius r whose (2r+1)^2 average brings sigma to the tuned level (0 if already there)."""
    if sigma_m <= settings.tuned_sigma_m:
        return 0
    n_needed = (sigma_m / settings.tuned_sigma_m) ** 2 / settings.window_efficiency
    r = int(np.ceil((np.sqrt(n_needed) - 1.0) / 2.0))
    return int(min(max(r, 1), settings.max_filter_radius_px))


def denoise_depth(depth_m: NDArray[np.float32], valid: NDArray[np.bool_], radius_px: int, k_per_m: float,
                  gate_sigmas: float) -> NDArray[np.float32]:
    """Edge-preserving mean: each valid pixel becomes the mean of the valid neighbours in its window that lie
    within ``gate_sigmas`` * sigma(z) of the window's median; invalid pixels stay 0."""
    if radius_px <= 0 or not valid.any():
        return depth_m
    rows, cols = np.nonzero(valid.any(axis=1))[0], np.nonzero(valid.any(axis=0))[0]
    v0, v1, u0, u1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
    out = np.zeros_like(depth_m)
    out[v0:v1, u0:u1] = _denoise_window(depth_m[v0:v1, u0:u1], valid[v0:v1, u0:u1], radius_px, k_per_m,
                                        gate_sigmas)
    return out


def _denoise_window(depth_m: NDArray[np.float32], valid: NDArray[np.bool_], radius_px: int, k_per_m: float,
                    gate_sigmas: float) -> NDArray[np.float32]:
    import cv2

    d = np.where(valid, depth_m, np.float32(0.0)).astype(np.float32)
    # a robust centre per pixel: the median of the 5x5 window over valid readings (invalid ones are 0, so
    # replace them by the pixel's own value first to keep them from pulling the median down)
    fill = np.float32(np.median(d[valid], overwrite_input=True) if valid.any() else 0.0)
    centre = cv2.medianBlur(np.where(valid, d, fill), 5)
    gate = np.float32(gate_sigmas * k_per_m) * centre * centre
    total = np.zeros_like(d)
    count = np.zeros_like(d)
    h, w = d.shape
    padded = np.pad(d, radius_px, mode="constant")
    # the same sums as `total += where(use, shifted, 0)`, in buffers reused in place (adding 0.0 to a total
    # that is never -0.0 leaves it as it was, so skipping the unused pixels changes no bit)
    spread = np.empty_like(d)
    use = np.empty(d.shape, dtype=bool)
    for dv in range(-radius_px, radius_px + 1):
        for du in range(-radius_px, radius_px + 1):
            shifted = padded[radius_px + dv:radius_px + dv + h, radius_px + du:radius_px + du + w]
            np.abs(np.subtract(shifted, centre, out=spread), out=spread)
            np.logical_and(shifted > 0, np.less_equal(spread, gate, out=use), out=use)
            np.add(total, shifted, out=total, where=use)
            count += use
    out = np.where(valid & (count > 0), total / np.maximum(count, 1), np.float32(0.0))
    return out.astype(np.float32)


def measure(depth_m: NDArray[np.float32], valid: NDArray[np.bool_], settings: NoiseSettings) -> NoiseEstimate:
    """Estimate the frame's noise and choose the denoising that brings it to the tuned level."""
    k = estimate_noise_coefficient(depth_m, valid)
    z = float(np.median(depth_m[valid], overwrite_input=True)) if valid.any() else 0.0  # a copy: ours to reorder
    sigma = k * z * z
    radius = filter_radius_for(sigma, settings) if settings.adapt else 0
    n = (2 * radius + 1) ** 2
    after = sigma / np.sqrt(max(1.0, n * settings.window_efficiency)) if radius else sigma
    return NoiseEstimate(k_per_m=k, working_depth_m=z, sigma_m=sigma, filter_radius_px=radius,
                         sigma_after_m=float(after))


def height_spread_m(heights: NDArray[np.float64]) -> float:
    """Robust standard deviation of the table points' heights about the fitted plane."""
    if heights.size < 20:
        return 0.0
    return float(_MAD_TO_SIGMA * np.median(np.abs(heights - np.median(heights))))


def adapt_segmentation(seg: SegmentationSettings, sigma_height_m: float, settings: NoiseSettings
                       ) -> SegmentationSettings:
    """The tuned thresholds, widened where the measured height spread needs more room."""
    if not settings.adapt or sigma_height_m <= 0:
        return seg
    return seg.model_copy(update={
        "plane_distance_m": max(seg.plane_distance_m, settings.plane_sigmas * sigma_height_m),
        "min_height_m": max(seg.min_height_m, settings.height_sigmas * sigma_height_m),
        "top_band_m": max(seg.top_band_m, settings.top_band_sigmas * sigma_height_m),
    })


def cluster_radius_m(points: NDArray[np.float64], seg: SegmentationSettings, settings: NoiseSettings) -> float:
    """DBSCAN radius: the tuned one, or a few times the median nearest-neighbour spacing if that is larger."""
    if not settings.adapt or len(points) < 10:
        return seg.cluster_eps_m
    dist, _ = cKDTree(points).query(points, k=2)
    spacing = float(np.median(dist[:, 1]))
    return max(seg.cluster_eps_m, settings.cluster_spacings * spacing)
