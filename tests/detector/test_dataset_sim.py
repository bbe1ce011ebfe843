"""`bt-grasp detector dataset` in the simulator: a small dataset of a household scene and a primitives scene;
every label inside its image, each object's label covers the object's visible mask (IoU > 0.8 with the mask's
minAreaRect, computed here from a fresh rendering of the same picture), and the same seed writes the same bytes."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from bt_grasp.cli.main import main
from bt_grasp.detector.dataset import dataset_classes, object_class, read_label_file
from bt_grasp.interfaces import Mount
from bt_grasp.scene.format import load_scene
from bt_grasp.sim.labelling import SegmentationCamera, build_world, randomised_scene

pytestmark = pytest.mark.sim

ROOT = Path(__file__).resolve().parents[2]
SCENES = [ROOT / "scenes" / "household_clear.yaml", ROOT / "scenes" / "tabletop.yaml"]
SEED, IMAGES, MIN_PIXELS = 7, 2, 60


@pytest.fixture(scope="module")
def datasets(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    cache = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BT_GRASP_CACHE_DIR", str(cache))
        out = []
        for name in ("a", "b"):
            folder = tmp_path_factory.mktemp(name)
            argv = ["detector", "dataset", "--scenes", *map(str, SCENES), "--images", str(IMAGES),
                    "--out", str(folder), "--seed", str(SEED), "--min-pixels", str(MIN_PIXELS)]
            assert main(argv) == 0
            out.append(folder)
    return out[0], out[1]


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_same_seed_same_bytes(datasets: tuple[Path, Path]) -> None:
    a, b = datasets
    files = _files(a)
    expected = {"data.yaml", "manifest.yaml", "preview.png", *(f"images/{i:05d}.png" for i in range(IMAGES)),
                *(f"labels/{i:05d}.txt" for i in range(IMAGES))}
    assert set(files) == expected
    assert files == _files(b)


def test_labels_are_inside_the_image_and_name_known_classes(datasets: tuple[Path, Path]) -> None:
    a, _ = datasets
    names = yaml.safe_load((a / "data.yaml").read_text())["names"]
    assert names == dict(enumerate(dataset_classes()))
    total = 0
    for label_file in sorted((a / "labels").iterdir()):
        for line in label_file.read_text().splitlines():
            parts = line.split()
            assert len(parts) == 9
            assert 0 <= int(parts[0]) < len(names)
            assert all(0.0 <= float(v) <= 1.0 for v in parts[1:])
            total += 1
    assert total >= 4  # both scenes' pictures hold several visible objects


def _poly_mask(corners: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    canvas = np.zeros(shape[:2], np.uint8)
    cv2.fillPoly(canvas, [np.round(corners).astype(np.int32)], 1)
    return canvas.astype(bool)


@pytest.mark.parametrize("index", range(IMAGES))
def test_each_label_covers_its_objects_mask(datasets: tuple[Path, Path], index: int,
                                            monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path))
    a, _ = datasets
    scene = SCENES[index % len(SCENES)]
    config = load_scene(scene)
    rng = np.random.default_rng([SEED, index])
    drawn, what = randomised_scene(config, rng, Mount(config.camera.mount))
    world, _ = build_world(scene, drawn, what, rng)
    masks = SegmentationCamera(world).masks()
    image = cv2.imread(str(a / "images" / f"{index:05d}.png"))
    h, w = image.shape[:2]
    labels = read_label_file(a / "labels" / f"{index:05d}.txt", w, h)
    classes = dataset_classes()
    visible = {name: m for name, m in masks.items() if m.sum() >= MIN_PIXELS}
    assert len(labels) == len(visible) >= 2
    unmatched = list(labels)
    for placed in world.placed:
        mask = visible.get(placed.spec.name)
        if mask is None:
            continue
        class_id = classes.index(object_class(placed.spec.shape, placed.spec.mesh, scene, placed.spec.name))
        ys, xs = np.nonzero(mask)
        rect = cv2.boxPoints(cv2.minAreaRect(np.stack([xs, ys], 1).astype(np.float32)))
        rect_mask = _poly_mask(rect, mask.shape)
        best = max((lab for lab in unmatched if lab[0] == class_id),
                   key=lambda lab: (_poly_mask(lab[1], mask.shape) & mask).sum())
        box = _poly_mask(best[1], mask.shape)
        iou = (box & rect_mask).sum() / (box | rect_mask).sum()
        assert iou > 0.8, (placed.spec.name, iou)
        assert (box & mask).sum() / mask.sum() > 0.98, placed.spec.name
        unmatched.remove(best)
    assert unmatched == []
