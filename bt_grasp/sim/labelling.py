"""Labelled pictures for the learned detector's dataset (`bt-grasp detector dataset`): a tool, not the pipeline.

It reads the simulator's truth on purpose, and only here and in the oracle: each object's visible mask comes from
a segmentation camera (SAPIEN's ``default`` shader pack, which draws per-entity ids; bt_grasp's own pack draws
colour and position only) placed exactly where the pipeline's camera is, with its intrinsics. Its first picture
in a process pays the pack's image-based-lighting set-up (about 12 s on lavapipe), later ones ~0.15 s.

Domain randomisation per picture, all drawn from ``[seed, index]``: the scene's own seeded draw (object subset,
rest poses, positions, yaws) from a world seed, the lights (ambient level, the sun's direction and strength), the
table's colour, the camera's pose jittered around its mount (eye-to-hand: up to 3 cm and 3 degrees; eye-in-hand:
1 cm and 3 degrees), the mount itself when both are asked for, and the camera's colour noise.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.detector.dataset import (
    ObbLabel,
    data_yaml,
    dataset_classes,
    draw_labels,
    label_from_mask,
    label_lines,
    object_class,
    preview_grid,
)
from bt_grasp.errors import InputError
from bt_grasp.interfaces import Mount
from bt_grasp.output_files import check_output_folder, make_output_folder, write_output_file
from bt_grasp.scene.format import Light, Scene, load_scene
from bt_grasp.sim.world import World

log = logging.getLogger(__name__)

#: camera pose jitter around the mount: (position m, angle deg) for each mount
JITTER = {Mount.EYE_TO_HAND: (0.03, 3.0), Mount.EYE_IN_HAND: (0.01, 3.0)}
MOUNT_CHOICES = ("scene", "eye-to-hand", "eye-in-hand", "both")
PREVIEW_TILES = 4


def _default_shader_dir() -> str:
    return os.path.join(os.path.dirname(sapien.__file__), "vulkan_shader", "default")


@dataclass(frozen=True)
class Randomisation:
    """What was drawn for one picture (written to the dataset's manifest)."""

    scene: str
    world_seed: int
    mount: str
    table_rgb: tuple[float, float, float]
    ambient: float
    sun_direction: tuple[float, float, float]
    sun: float


def randomised_scene(config: Scene, rng: np.random.Generator, mount: Mount) -> tuple[Scene, Randomisation]:
    """``config`` with the lights, the table colour and the camera pose drawn from ``rng``."""
    grey = float(rng.uniform(0.25, 0.85))
    r, g, b = (float(np.clip(grey + rng.uniform(-0.12, 0.12), 0.05, 0.95)) for _ in range(3))
    table_rgb = (r, g, b)
    ambient = float(rng.uniform(0.2, 0.55))
    azimuth, elevation = float(rng.uniform(0, 2 * math.pi)), math.radians(float(rng.uniform(40, 85)))
    sun_direction = (math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                     -math.sin(elevation))
    sun = float(rng.uniform(0.5, 1.0))
    shadow = any(light.shadow for light in config.lights if light.kind == "directional")
    lights = (
        Light(kind="ambient", color=(ambient, ambient, ambient)),
        Light(kind="directional", direction=sun_direction, color=(sun, sun, sun), shadow=shadow),
    )
    move_m, turn_deg = JITTER[mount]
    camera = config.camera
    if mount == Mount.EYE_TO_HAND:
        e2h = camera.eye_to_hand
        e2h = e2h.model_copy(update={
            "position_m": tuple(float(v) for v in np.add(e2h.position_m, rng.uniform(-move_m, move_m, 3))),
            "look_at_m": tuple(float(v) for v in np.add(e2h.look_at_m, rng.uniform(-move_m, move_m, 3))),
            "roll_deg": e2h.roll_deg + float(rng.uniform(-turn_deg, turn_deg)),
        })
        camera = camera.model_copy(update={"eye_to_hand": e2h, "mount": mount.value})
    else:
        eih = camera.eye_in_hand
        eih = eih.model_copy(update={
            "xyz_m": tuple(float(v) for v in np.add(eih.xyz_m, rng.uniform(-move_m, move_m, 3))),
            "rpy_deg": tuple(float(v) for v in np.add(eih.rpy_deg, rng.uniform(-turn_deg, turn_deg, 3))),
        })
        camera = camera.model_copy(update={"eye_in_hand": eih, "mount": mount.value})
    table = config.table.model_copy(update={"color": table_rgb})
    drawn = config.model_copy(update={"lights": lights, "camera": camera, "table": table})
    world_seed = int(rng.integers(0, 2**31 - 1))
    return drawn, Randomisation(config.name, world_seed, mount.value, table_rgb, ambient, sun_direction, sun)


class SegmentationCamera:
    """A camera at the pipeline camera's place with its intrinsics, drawing per-entity ids."""

    def __init__(self, world: World) -> None:
        source = world.camera._component  # the pipeline's camera component: same pose, same intrinsics
        camera = sapien.render.RenderCameraComponent(source.width, source.height, _default_shader_dir())
        camera.set_fovy(source.fovy, compute_x=True)
        camera.near, camera.far = source.near, source.far
        camera.set_local_pose(source.get_local_pose())
        source.entity.add_component(camera)
        self._world = world
        self._camera = camera

    def masks(self) -> dict[str, NDArray[np.bool_]]:
        """Each object's visible pixels, by object name (empty masks included)."""
        self._world.scene.update_render()
        self._camera.take_picture()
        ids = self._camera.get_picture("Segmentation")[..., 1]
        return {name: ids == entity.per_scene_id for name, entity in self._world.objects.items()}


def labelled_picture(scene_path: Path, config: Scene, rng: np.random.Generator, mount: Mount, min_pixels: int,
                     classes: Sequence[str]) -> tuple[NDArray[np.uint8], list[ObbLabel], Randomisation]:
    """One randomised picture of ``config`` and the oriented-box labels of the objects visible in it."""
    drawn, what = randomised_scene(config, rng, mount)
    world = World(drawn, what.world_seed, camera_mount=mount.value, source=scene_path)
    frame = world.camera.capture()
    assert frame is not None
    masks = SegmentationCamera(world).masks()
    labels = []
    for placed in world.placed:
        spec = placed.spec
        class_id = classes.index(object_class(spec.shape, spec.mesh, scene_path, spec.name))
        label = label_from_mask(masks[spec.name], class_id, min_pixels)
        if label is not None:
            labels.append(label)
    return frame.color, labels, what


@dataclass(frozen=True)
class DatasetSummary:
    images: int
    labels: int
    per_class: dict[str, int]


def _png(bgr: NDArray[Any]) -> bytes:
    ok, data = cv2.imencode(".png", bgr)
    if not ok:
        raise ValueError("a picture did not encode as PNG")
    return data.tobytes()


def _mount_for(rule: str, config: Scene, index: int) -> Mount:
    if rule == "scene":
        return Mount(config.camera.mount)
    if rule == "both":
        return (Mount.EYE_TO_HAND, Mount.EYE_IN_HAND)[index % 2]
    return Mount(rule)


def make_dataset(scenes: Sequence[Path], images: int, out: Path, seed: int, *, mount: str = "scene",
                 min_pixels: int = 60) -> DatasetSummary:
    """Write ``images`` labelled pictures of ``scenes`` (taken in turn) to ``out`` in the Ultralytics OBB layout:
    ``images/NNNNN.png``, ``labels/NNNNN.txt``, ``data.yaml``, ``manifest.yaml`` (what was drawn for each picture)
    and ``preview.png`` (the first pictures with their labels drawn). Same arguments, same bytes."""
    import yaml

    if mount not in MOUNT_CHOICES:
        raise InputError("--mount", f"expected one of {', '.join(MOUNT_CHOICES)}, got '{mount}'")
    check_output_folder(out, "--out")
    if out.is_dir() and any(out.iterdir()):
        raise InputError("--out", f"'{out}' holds files already; give a new or empty folder (a dataset written over "
                                  "another one mixes their pictures and labels)")
    configs = [(Path(s), load_scene(s)) for s in scenes]
    classes = dataset_classes()
    for path, config in configs:  # every object must have a class before anything is rendered
        for obj in config.objects:
            object_class(obj.shape, obj.mesh, path, obj.name)
    make_output_folder(out / "images", "--out")
    make_output_folder(out / "labels", "--out")
    manifest: list[dict[str, object]] = []
    tiles: list[NDArray[np.uint8]] = []
    per_class = dict.fromkeys(classes, 0)
    total = 0
    for index in range(images):
        path, config = configs[index % len(configs)]
        rng = np.random.default_rng([seed, index])
        rgb, labels, what = labelled_picture(path, config, rng, _mount_for(mount, config, index), min_pixels,
                                             classes)
        stem = f"{index:05d}"
        write_output_file(out / "images" / f"{stem}.png", _png(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)), "--out")
        write_output_file(out / "labels" / f"{stem}.txt", label_lines(labels, rgb.shape[1], rgb.shape[0]), "--out")
        for label in labels:
            per_class[classes[label.class_id]] += 1
        total += len(labels)
        manifest.append({"image": f"images/{stem}.png", "scene": str(path), "world_seed": what.world_seed,
                         "mount": what.mount, "table_rgb": [round(v, 4) for v in what.table_rgb],
                         "ambient": round(what.ambient, 4), "sun": round(what.sun, 4),
                         "sun_direction": [round(v, 4) for v in what.sun_direction],
                         "objects": [classes[label.class_id] for label in labels]})
        if len(tiles) < PREVIEW_TILES:
            tiles.append(draw_labels(rgb, labels, classes))
        log.info("picture %d/%d: %d labels", index + 1, images, len(labels))
    write_output_file(out / "data.yaml", data_yaml(classes), "--out")
    header = {"made_by": "bt-grasp detector dataset", "scenes": [str(p) for p, _ in configs], "images": images,
              "seed": seed, "mount": mount, "min_pixels": min_pixels, "pictures": manifest}
    write_output_file(out / "manifest.yaml", yaml.safe_dump(header, sort_keys=False), "--out")
    if tiles:
        write_output_file(out / "preview.png", _png(preview_grid(tiles)), "--out")
    return DatasetSummary(images, total, {k: v for k, v in per_class.items() if v})
