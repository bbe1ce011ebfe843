"""Labelled pictures for the learned detector's dataset (`bt-grasp detector dataset`): a tool, not the pipeline.

It reads the simulator's truth on purpose, and only here and in the oracle: each object's visible mask comes from
a segmentation camera (SAPIEN's ``default`` shader pack, which draws per-entity ids; bt_grasp's own pack draws
colour and position only) placed exactly where the pipeline's camera is, with its intrinsics. Its first picture
in a process pays the pack's image-based-lighting set-up (about 12 s on lavapipe), later ones ~0.15 s.

Domain randomisation per picture, all drawn from ``[seed, index]``: the scene's own seeded draw (object subset,
rest poses, positions, yaws) from a world seed (drawn again when a draw cannot place its objects), the lights
(ambient level, the sun's direction and strength), the table's colour and surface (``bt_grasp.sim.table_texture``:
plain, wood, mottled, tiles or speckle), the arm's pose (its home joints jittered: always with the camera on the
wrist, so that it looks at other parts of the table from other heights and rolls; every other picture with the
camera on its stand, so that the arm stands elsewhere in view), the camera's pose jittered around its mount
(eye-to-hand: up to 3 cm and 3 degrees; eye-in-hand: 1 cm and 3 degrees), the mount itself when both are asked
for, and the camera's colour noise (the D435 model's Gaussian colour noise, its sigma drawn per picture).

The segmentation camera uses SAPIEN's ``trivial`` shader pack: it draws per-entity ids like the ``default`` pack
(the same labels, checked on the same pictures) without the image-based-lighting table the ``default`` pack builds
for every new scene (about 12 s per picture on lavapipe; ``trivial``: a few milliseconds).
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

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
from bt_grasp.errors import ConfigError, InputError
from bt_grasp.files.output_files import check_output_folder, make_output_folder, write_output_file
from bt_grasp.interfaces import Mount
from bt_grasp.scene.colors import rgb_of
from bt_grasp.scene.format import Light, Scene, load_scene
from bt_grasp.sim.poses import to_T
from bt_grasp.sim.table_texture import TEXTURE_KINDS, add_table_top, texture_image
from bt_grasp.sim.world import World

if TYPE_CHECKING:
    from cv2.typing import MatLike

log = logging.getLogger(__name__)

#: camera pose jitter around the mount: (position m, angle deg) for each mount
JITTER = {Mount.EYE_TO_HAND: (0.03, 3.0), Mount.EYE_IN_HAND: (0.01, 3.0)}
#: eye-to-hand: the arm's home joints jittered by up to this much (rad), joint by joint (shoulder pan ... wrist 3)
ARM_JITTER_RAD = (0.35, 0.2, 0.2, 0.25, 0.2, 0.6)
#: eye-in-hand: the arm's joints drawn in home + [low, high] (rad) until the camera's optical axis meets the table
#: inside the scene's workspace (grown by WRIST_VIEW_MARGIN_M) from at least WRIST_MIN_HEIGHT_M above the top
WRIST_Q_OFFSET_RAD = ((-0.8, 0.3), (-0.25, 0.2), (-0.5, 0.1), (-0.5, 0.15), (-0.2, 0.2), (-0.6, 0.6))
WRIST_VIEW_MARGIN_M = 0.05
WRIST_MIN_HEIGHT_M = 0.3
WRIST_TRIES = 50
#: the camera's colour noise: its sigma (8-bit levels) drawn in this range (the scenes' D435 model has 2)
COLOR_SIGMA = (1.0, 5.0)
#: one copy of a table texture covers this much of the table, m (drawn per picture)
TEXTURE_REPEAT_M = (0.4, 1.2)
#: the share of pictures drawn with the scene's own look: its table colour (jittered by up to SCENE_LOOK_JITTER
#: per channel), plain, and its own lights: what the pipeline's camera sees. A model trained on the drawn greys
#: and textures alone missed objects on the household scene's wood-coloured table (a lying green bottle scored
#: 0.12 there and 0.93 with the table recoloured grey)
SCENE_LOOK_SHARE = 1 / 3
SCENE_LOOK_JITTER = 0.04
#: a scene draw that cannot place its objects is drawn again with a new world seed, up to this many times
WORLD_TRIES = 20
MOUNT_CHOICES = ("scene", "eye-to-hand", "eye-in-hand", "both")
PREVIEW_TILES = 4


def _segmentation_shader_dir() -> str:
    return os.path.join(os.path.dirname(sapien.__file__), "vulkan_shader", "trivial")


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
    table_texture: str
    texture_seed: int
    texture_repeat_m: float
    arm_q_rad: tuple[float, ...]
    color_sigma: float
    #: the scene's own table colour, plain, and its own lights (SCENE_LOOK_SHARE of the pictures)
    scene_look: bool = False


def randomised_scene(config: Scene, rng: np.random.Generator, mount: Mount) -> tuple[Scene, Randomisation]:
    """``config`` with the lights, the table colour and surface, the arm's home pose (eye-to-hand: jittered half
    the time; eye-in-hand: :func:`aim_wrist_camera` draws it once the world is built), the camera pose and its
    colour noise drawn from ``rng``."""
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
    texture = TEXTURE_KINDS[int(rng.integers(len(TEXTURE_KINDS)))]
    texture_seed = int(rng.integers(0, 2**31 - 1))
    repeat_m = float(rng.uniform(*TEXTURE_REPEAT_M))
    arm_q = np.asarray(config.robot.home_q_rad, dtype=float)
    jitter = rng.uniform(-1.0, 1.0, 6) * np.asarray(ARM_JITTER_RAD)
    if mount == Mount.EYE_TO_HAND and rng.random() < 0.5:
        arm_q = arm_q + jitter
    robot = config.robot.model_copy(update={"home_q_rad": tuple(float(v) for v in arm_q)})
    color_sigma = float(rng.uniform(*COLOR_SIGMA))
    camera = camera.model_copy(update={"noise": camera.noise.model_copy(update={"color_sigma": color_sigma})})
    drawn = config.model_copy(update={"lights": lights, "camera": camera, "table": table, "robot": robot})
    world_seed = int(rng.integers(0, 2**31 - 1))
    scene_look = bool(rng.random() < SCENE_LOOK_SHARE)
    if scene_look:  # the pipeline's own look: the scene's table colour (jittered), plain, the scene's lights
        own = rgb_of(config.table.color)
        table_rgb = tuple(float(np.clip(v + rng.uniform(-SCENE_LOOK_JITTER, SCENE_LOOK_JITTER), 0.0, 1.0))
                          for v in own)  # type: ignore[assignment]
        texture = "plain"
        drawn = drawn.model_copy(update={"lights": config.lights,
                                         "table": config.table.model_copy(update={"color": table_rgb})})
        ambient = next((float(np.mean(x.color)) for x in config.lights if x.kind == "ambient"), 0.0)
        sun_light = next((x for x in config.lights if x.kind == "directional"), None)
        sun = float(np.mean(sun_light.color)) if sun_light is not None else 0.0
        if sun_light is not None:
            sun_direction = tuple(float(v) for v in sun_light.direction)  # type: ignore[assignment]
    return drawn, Randomisation(config.name, world_seed, mount.value, table_rgb, ambient, sun_direction, sun,
                                texture, texture_seed, repeat_m, tuple(float(v) for v in arm_q), color_sigma,
                                scene_look)


def view_centre_xy(world: World) -> tuple[float, float, float] | None:
    """Where the camera's optical axis meets the table top (x, y) and the camera's height; None looking up."""
    T = to_T(world.camera._component.get_global_pose())  # SAPIEN's camera looks along its +x
    position, forward = T[:3, 3], T[:3, 0]
    if forward[2] >= -1e-6:
        return None
    hit = position - position[2] / forward[2] * forward
    return float(hit[0]), float(hit[1]), float(position[2])


def aim_wrist_camera(world: World, rng: np.random.Generator) -> tuple[float, ...]:
    """Eye-in-hand: place the arm (before any picture; objects are not touched) at joints drawn around home until
    the camera looks at the workspace from high enough (the last draw after :data:`WRIST_TRIES`); returns them."""
    home = np.asarray(world.config.robot.home_q_rad, dtype=float)
    low, high = (np.array(v, dtype=float) for v in zip(*WRIST_Q_OFFSET_RAD, strict=True))
    ws, margin = world.config.workspace, WRIST_VIEW_MARGIN_M
    q = home
    for _ in range(WRIST_TRIES):
        q = home + rng.uniform(low, high)
        world.robot.reset(q)
        seen = view_centre_xy(world)
        if seen is not None and ws.x_m[0] - margin <= seen[0] <= ws.x_m[1] + margin and \
                ws.y_m[0] - margin <= seen[1] <= ws.y_m[1] + margin and seen[2] >= WRIST_MIN_HEIGHT_M:
            break
    return tuple(float(v) for v in q)


def build_world(scene_path: Path, drawn: Scene, what: Randomisation,
                rng: np.random.Generator) -> tuple[World, Randomisation]:
    """The drawn scene's world with its table surface and, eye-in-hand, the arm aimed (:func:`aim_wrist_camera`);
    a world seed whose draw cannot place the objects is replaced by another from ``rng`` (up to
    :data:`WORLD_TRIES` draws). Returns the world and what was drawn (the world seed and arm joints used)."""
    seed = what.world_seed
    for _ in range(WORLD_TRIES):
        try:
            world = World(drawn, seed, camera_mount=what.mount, source=scene_path)
        except ConfigError as exc:
            log.debug("world seed %d: %s; drawing another", seed, exc)
            seed = int(rng.integers(0, 2**31 - 1))
            continue
        rgba = texture_image(what.table_texture, what.table_rgb, np.random.default_rng(what.texture_seed))
        if rgba is not None:
            table = drawn.table
            add_table_top(world.scene, rgba, table.center_xy_m, table.size_m[:2], what.texture_repeat_m)
        arm_q = aim_wrist_camera(world, rng) if world.camera_mount == Mount.EYE_IN_HAND else what.arm_q_rad
        return world, replace(what, world_seed=seed, arm_q_rad=arm_q)
    raise ConfigError(scene_path, f"no placement of its objects in {WORLD_TRIES} draws", "objects")


class SegmentationCamera:
    """A camera at the pipeline camera's place with its intrinsics, drawing per-entity ids."""

    def __init__(self, world: World) -> None:
        source = world.camera._component  # the pipeline's camera component: same pose, same intrinsics
        camera = sapien.render.RenderCameraComponent(source.width, source.height, _segmentation_shader_dir())
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
    world, what = build_world(scene_path, drawn, what, rng)
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


def _png(bgr: MatLike) -> bytes:
    ok, data = cv2.imencode(".png", bgr)
    if not ok:
        raise ValueError("a picture did not encode as PNG")
    return data.tobytes()


def _mount_for(rule: str, config: Scene, index: int, scenes: int) -> Mount:
    if rule == "scene":
        return Mount(config.camera.mount)
    if rule == "both":  # each scene's pictures alternate (index // scenes: with an even number of scenes, index % 2
        return (Mount.EYE_TO_HAND, Mount.EYE_IN_HAND)[(index // scenes) % 2]  # would give each scene one mount)
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
        camera_mount = _mount_for(mount, config, index, len(configs))
        rgb, labels, what = labelled_picture(path, config, rng, camera_mount, min_pixels, classes)
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
                         "table_texture": what.table_texture, "texture_seed": what.texture_seed,
                         "texture_repeat_m": round(what.texture_repeat_m, 4),
                         "arm_q_rad": [round(v, 4) for v in what.arm_q_rad],
                         "color_sigma": round(what.color_sigma, 3), "scene_look": what.scene_look,
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
