"""Letterbox as Ultralytics' LetterBox(auto=False) draws it, and the way back (scale_boxes) exact."""

from __future__ import annotations

import numpy as np
import pytest

from bt_grasp.detector.letterbox import PAD_VALUE, LetterboxGeometry, letterbox, to_input_tensor


@pytest.mark.parametrize(
    ("original_hw", "input_hw", "gain", "resized_wh", "top", "left"),
    [
        # 480x640 into 320: half size, 320x240, 40 px of grey above and below
        ((480, 640), (320, 320), 0.5, (320, 240), 40, 0),
        # 720x1280 into 320: gain 0.25, 320x180, 70 above
        ((720, 1280), (320, 320), 0.25, (320, 180), 70, 0),
        # a portrait image into a landscape input: min(320/1000, 640/500) = 0.32 -> 160x320, 240 px left and right
        ((1000, 500), (320, 640), 0.32, (160, 320), 0, 240),
        # odd sizes: min(320/481, 480/722) = 480/722 -> 480 x 319.78, drawn 320 high, the 0.22 px left over is
        # no border (round(0.11 - 0.1) = 0)
        ((481, 722), (320, 480), 480 / 722, (480, 320), 0, 0),
        # 0.64 -> 320 x 213.12 drawn 213 high; 107 px of grey = 53 above (round(53.5 - 0.1)) + 54 below
        ((333, 500), (320, 320), 0.64, (320, 213), 53, 0),
    ],
)
def test_geometry_matches_ultralytics_arithmetic(original_hw, input_hw, gain, resized_wh, top, left) -> None:
    g = LetterboxGeometry.of(original_hw, input_hw)
    assert g.gain == pytest.approx(gain, rel=1e-12)
    assert g.resized_wh == resized_wh
    assert (g.pad_y, g.pad_x) == (top, left)


@pytest.mark.parametrize(("original_hw", "input_hw"), [((480, 640), (320, 320)), ((333, 500), (320, 320)),
                                                       ((1000, 500), (320, 640)), ((720, 1280), (384, 640))])
def test_image_is_placed_where_the_geometry_says(original_hw, input_hw) -> None:
    h0, w0 = original_hw
    image = np.full((h0, w0, 3), 30, dtype=np.uint8)
    # a 40x40 white square whose centre lands on a known input pixel
    image[h0 // 2 - 20 : h0 // 2 + 20, w0 // 2 - 20 : w0 // 2 + 20] = 250
    boxed, g = letterbox(image, input_hw)
    assert boxed.shape == (*input_hw, 3)
    top = g.pad_y
    assert (boxed[:top] == PAD_VALUE).all()
    assert (boxed[top + g.resized_wh[1] :] == PAD_VALUE).all()
    assert (boxed[:, : g.pad_x] == PAD_VALUE).all()
    assert (boxed[:, g.pad_x + g.resized_wh[0] :] == PAD_VALUE).all()
    centre_in = g.to_input(np.array([w0 / 2, h0 / 2]))
    x, y = int(centre_in[0]), int(centre_in[1])
    assert boxed[y, x].tolist() == [250, 250, 250]
    tensor = to_input_tensor(boxed)
    assert tensor.shape == (1, 3, *input_hw) and tensor.dtype == np.float32
    assert tensor[0, :, y, x] == pytest.approx([250 / 255] * 3)


def test_round_trip_is_exact() -> None:
    rng = np.random.default_rng(23)
    for original_hw, input_hw in [((480, 640), (320, 320)), ((333, 500), (320, 320)), ((720, 1280), (384, 640))]:
        g = LetterboxGeometry.of(original_hw, input_hw)
        points = rng.uniform(0, 1, size=(50, 2)) * [original_hw[1], original_hw[0]]
        back = g.to_original(g.to_input(points))
        np.testing.assert_allclose(back, points, rtol=0, atol=1e-9)
        # and the forward mapping is the scale_boxes formula written out: (x - pad) / gain
        inp = g.to_input(points)
        np.testing.assert_allclose((inp[:, 0] - g.pad_x) / g.gain, points[:, 0], atol=1e-9)
