"""Colour evidence: HSV thresholding, morphology and minimum-area rectangles on the colour image."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_grasp.perception.config import ColorSettings, HsvRange


def to_hsv(color_rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    return np.asarray(cv2.cvtColor(color_rgb, cv2.COLOR_RGB2HSV), dtype=np.uint8)


def _in_range(hsv: NDArray[np.uint8], r: HsvRange) -> NDArray[np.bool_]:
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    sv = (s >= r.s_min) & (s <= r.s_max) & (v >= r.v_min) & (v <= r.v_max)
    hue = (h >= r.h_min) & (h <= r.h_max) if r.h_min <= r.h_max else (h >= r.h_min) | (h <= r.h_max)
    return np.asarray(sv & hue)


def pixel_matches(hsv_values: NDArray[np.uint8], ranges: tuple[HsvRange, ...]) -> NDArray[np.bool_]:
    """Which of the given HSV values ((..., 3) array) fall inside any of the boxes."""
    out = np.zeros(hsv_values.shape[:-1], dtype=bool)
    for r in ranges:
        out |= _in_range(hsv_values, r)
    return out


@dataclass(frozen=True)
class ColorBlob:
    """A connected region of the mask: its minimum-area rectangle ((cx, cy), (w, h), angle_deg) and area."""

    rect: tuple[tuple[float, float], tuple[float, float], float]
    area_px: float


def color_mask(hsv: NDArray[np.uint8], ranges: tuple[HsvRange, ...], settings: ColorSettings) -> NDArray[np.uint8]:
    """Binary mask (0/255) of the colour after an opening (speckle) and a closing (holes)."""
    mask = pixel_matches(hsv, ranges).astype(np.uint8) * 255
    k = settings.morph_kernel_px
    if k > 1:
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
        mask = np.asarray(cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel), dtype=np.uint8)
        mask = np.asarray(cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel), dtype=np.uint8)
    return mask


def blobs(mask: NDArray[np.uint8], settings: ColorSettings) -> list[ColorBlob]:
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    out = []
    for contour in contours:
        area = float(cv2.contourArea(contour))
        if area >= settings.min_area_px:
            (cx, cy), (w, h), angle = cv2.minAreaRect(contour)
            out.append(ColorBlob(((float(cx), float(cy)), (float(w), float(h)), float(angle)), area))
    out.sort(key=lambda b: b.area_px, reverse=True)
    return out


def classify(hsv_values: NDArray[np.uint8], settings: ColorSettings) -> tuple[str | None, float]:
    """The colour name most of these pixels match, and that fraction (None when under one half)."""
    best, best_fraction = None, 0.0
    if len(hsv_values) == 0:
        return None, 0.0
    for name, ranges in settings.ranges.items():
        fraction = float(pixel_matches(hsv_values, ranges).mean())
        if fraction > best_fraction:
            best, best_fraction = name, fraction
    return (best, best_fraction) if best_fraction >= 0.5 else (None, best_fraction)


def dominant_color(
    rgb_values: NDArray[np.uint8], hsv_values: NDArray[np.uint8], settings: ColorSettings
) -> tuple[str, tuple[int, int, int]]:
    """The name matched by the most of these pixels ("" when none matches any) and their median RGB: an
    attribute of an object already found by geometry, whatever share of it the colour covers."""
    if len(rgb_values) == 0:
        return "", (0, 0, 0)
    rgb = tuple(int(c) for c in np.median(rgb_values.reshape(-1, 3), axis=0))
    best, best_fraction = "", 0.0
    for name, ranges in settings.ranges.items():
        fraction = float(pixel_matches(hsv_values, ranges).mean())
        if fraction > best_fraction:
            best, best_fraction = name, fraction
    return best, (rgb[0], rgb[1], rgb[2])
