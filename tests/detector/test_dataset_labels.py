"""Oriented-box labels from masks and the Ultralytics OBB label format, without the simulator."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from bt_grasp.detector.dataset import (
    ObbLabel,
    data_yaml,
    dataset_classes,
    label_from_mask,
    label_lines,
    object_class,
    read_label_file,
)
from bt_grasp.errors import ConfigError


def _polygon_mask(corners: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    canvas = np.zeros(shape, np.uint8)
    cv2.fillPoly(canvas, [np.round(corners).astype(np.int32)], 1)
    return canvas.astype(bool)


def test_a_rotated_rectangle_mask_gets_its_own_box() -> None:
    truth = cv2.boxPoints(((200.0, 150.0), (120.0, 36.0), 30.0))
    mask = _polygon_mask(truth, (300, 400))
    label = label_from_mask(mask, 4, min_pixels=50)
    assert label is not None and label.class_id == 4 and label.pixels == int(mask.sum())
    box = _polygon_mask(label.corners_px, (300, 400))
    assert (box & mask).sum() / mask.sum() > 0.99  # the box covers the mask
    assert (box & mask).sum() / (box | mask).sum() > 0.9  # and little else
    (cx, cy), (w, h), _ = cv2.minAreaRect(label.corners_px.astype(np.float32))
    assert (cx, cy) == pytest.approx((200.0, 150.0), abs=1.0)
    # fillPoly draws the boundary's pixels too (about 1 px more each way) and the label covers whole pixels (+1)
    assert sorted((w, h)) == pytest.approx([36.0 + 2, 120.0 + 2], abs=1.0)


def test_small_or_hidden_objects_get_no_label() -> None:
    mask = np.zeros((100, 100), bool)
    assert label_from_mask(mask, 0, min_pixels=1) is None
    mask[10:15, 10:15] = True  # 25 px
    assert label_from_mask(mask, 0, min_pixels=26) is None
    assert label_from_mask(mask, 0, min_pixels=25) is not None


def test_label_lines_are_normalised_clipped_and_read_back(tmp_path: Path) -> None:
    inside = ObbLabel(3, np.array([[10.0, 20.0], [110.0, 20.0], [110.0, 60.0], [10.0, 60.0]]), 4000)
    across = ObbLabel(0, np.array([[-5.0, 470.0], [50.0, 470.0], [50.0, 490.0], [-5.0, 490.0]]), 900)
    text = label_lines([inside, across], 640, 480)
    lines = text.splitlines()
    assert lines[0] == "3 0.015625 0.041667 0.171875 0.041667 0.171875 0.125000 0.015625 0.125000"
    assert lines[1].split()[0] == "0"
    values = [float(v) for line in lines for v in line.split()[1:]]
    assert min(values) >= 0.0 and max(values) <= 1.0  # the box crossing the edge is clipped to the image
    path = tmp_path / "x.txt"
    path.write_text(text)
    (cls, corners), _ = read_label_file(path, 640, 480)
    assert cls == 3
    np.testing.assert_allclose(corners, inside.corners_px, atol=640 * 1e-6)


def test_classes_are_the_catalogue_then_the_primitives(tmp_path: Path) -> None:
    classes = dataset_classes()
    assert classes[-3:] == ("box", "cylinder", "sphere")
    for name in ("mug", "banana", "small_box", "pen", "bottle"):
        assert name in classes
    assert len(set(classes)) == len(classes)
    assert yaml.safe_load(data_yaml(classes))["names"] == dict(enumerate(classes))
    assert object_class("mesh", "../bt_grasp/assets/household/banana.obj", tmp_path / "s.yaml", "b1") == "banana"
    assert object_class("cylinder", None, tmp_path / "s.yaml", "c") == "cylinder"
    with pytest.raises(ConfigError, match=r"s.yaml: object 'duck' \(mesh meshes/duck.stl\) is not a household "
                                          r"catalogue object nor a primitive.* at objects.duck"):
        object_class("mesh", "meshes/duck.stl", tmp_path / "s.yaml", "duck")


def _cli_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "error: " in err and "\n" not in err and "Traceback" not in err
    return err


def test_dataset_command_refuses_bad_input_before_rendering(
    repo_root: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bt_grasp.cli.main import main

    base = ["detector", "dataset", "--images", "1", "--out", str(tmp_path / "ds")]
    assert main([*base, "--scenes", str(repo_root / "scenes" / "tabletop.yaml"), "--mount", "sideways"]) == 2
    assert "--mount: expected one of scene, eye-to-hand, eye-in-hand, both, got 'sideways'" in _cli_error(capsys)
    assert main([*base, "--scenes", str(tmp_path / "absent.yaml")]) == 2
    assert "absent.yaml" in _cli_error(capsys)
    # a mesh outside the household catalogue has no class: refused, the scene and the object named
    colourless = repo_root / "tests" / "data" / "scenes" / "colourless.yaml"
    assert main([*base, "--scenes", str(repo_root / "scenes" / "tabletop.yaml"), str(colourless)]) == 2
    err = _cli_error(capsys)
    assert "colourless.yaml: object '" in err and "is not a household catalogue object nor a primitive" in err
    assert not (tmp_path / "ds" / "images").exists()  # nothing was rendered or written
