"""Letterbox pre-processing exactly as Ultralytics' ``LetterBox(auto=False, center=True)`` does it for a
fixed-size export, and the inverse mapping (``ops.scale_boxes``) of pixel coordinates back to the original image."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

#: the grey Ultralytics pads with
PAD_VALUE = 114


@dataclass(frozen=True)
class LetterboxGeometry:
    """How an original image of ``original_hw`` was placed in the network input of ``input_hw``.

    ``gain`` is input pixels per original pixel; ``pad_x``/``pad_y`` the left/top border in input pixels, as
    ``ops.scale_boxes`` recomputes them (``round(... - 0.1)``), which equals the border LetterBox drew.
    """

    original_hw: tuple[int, int]
    input_hw: tuple[int, int]
    gain: float
    resized_wh: tuple[int, int]
    pad_x: int
    pad_y: int

    @classmethod
    def of(cls, original_hw: tuple[int, int], input_hw: tuple[int, int]) -> LetterboxGeometry:
        h0, w0 = original_hw
        h1, w1 = input_hw
        gain = min(h1 / h0, w1 / w0)
        resized_wh = (round(w0 * gain), round(h0 * gain))
        # the border LetterBox draws (left/top); scale_boxes recomputes the same numbers from the shapes
        pad_x = round((w1 - w0 * gain) / 2 - 0.1)
        pad_y = round((h1 - h0 * gain) / 2 - 0.1)
        return cls(original_hw, input_hw, gain, resized_wh, pad_x, pad_y)

    def to_original(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """Input-pixel points ``(..., 2)`` -> original-image pixels (``scale_boxes``' shift then divide)."""
        out = np.array(xy, dtype=np.float64, copy=True)
        out[..., 0] -= self.pad_x
        out[..., 1] -= self.pad_y
        return out / self.gain

    def to_input(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """Original-image pixels -> input pixels (the inverse of ``to_original``)."""
        out = np.asarray(xy, dtype=np.float64) * self.gain
        out[..., 0] += self.pad_x
        out[..., 1] += self.pad_y
        return out


def letterbox(image: NDArray[np.uint8], input_hw: tuple[int, int]) -> tuple[NDArray[np.uint8], LetterboxGeometry]:
    """Resize ``image`` (H, W, 3) keeping its aspect ratio (bilinear) and pad it with grey 114 to ``input_hw``,
    the padding split between both sides as Ultralytics splits it (``round(d - 0.1)`` before, ``round(d + 0.1)``
    after)."""
    h0, w0 = image.shape[:2]
    geometry = LetterboxGeometry.of((h0, w0), input_hw)
    h1, w1 = input_hw
    resized = image
    if (w0, h0) != geometry.resized_wh:
        resized = np.asarray(cv2.resize(image, geometry.resized_wh, interpolation=cv2.INTER_LINEAR), dtype=np.uint8)
    dw = (w1 - geometry.resized_wh[0]) / 2
    dh = (h1 - geometry.resized_wh[1]) / 2
    top, bottom = round(dh - 0.1), round(dh + 0.1)
    left, right = round(dw - 0.1), round(dw + 0.1)
    padded = cv2.copyMakeBorder(resized, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(PAD_VALUE,) * 3)
    return np.ascontiguousarray(padded, dtype=np.uint8), geometry


def to_input_tensor(image: NDArray[np.uint8]) -> NDArray[np.float32]:
    """A letterboxed RGB image (H, W, 3) -> the network's ``[1, 3, H, W]`` float32 in [0, 1]."""
    return np.ascontiguousarray(image.transpose(2, 0, 1)[None], dtype=np.float32) / np.float32(255.0)
