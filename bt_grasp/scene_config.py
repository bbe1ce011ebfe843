"""The scene file (``scenes/*.yaml``): table, robot mount, camera, lights, objects, randomisation.

Frames: the world frame has z up and its origin on the table top; the robot's ``base_link`` sits at
``robot.base_xyz_m``. Everything a robot would know from its installation drawing (the table, where the
robot is bolted, the camera's nominal mount) is here; the objects' drawn poses are the simulator's secret.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from bt_grasp.config import StrictModel, load_model

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Vec3 = tuple[float, float, float]
Range = tuple[float, float]

#: colour names a scene may use, as linear-ish sRGB in [0, 1]
COLOR_NAMES: dict[str, tuple[float, float, float]] = {
    "red": (0.85, 0.08, 0.08),
    "green": (0.10, 0.70, 0.15),
    "blue": (0.08, 0.20, 0.85),
    "yellow": (0.90, 0.80, 0.05),
    "orange": (0.95, 0.45, 0.05),
    "purple": (0.50, 0.10, 0.70),
    "white": (0.92, 0.92, 0.92),
    "grey": (0.5, 0.5, 0.5),
    "black": (0.05, 0.05, 0.05),
    "wood": (0.62, 0.48, 0.33),
}


class Physics(StrictModel):
    timestep_s: Annotated[float, Field(gt=0, le=0.004)] = 0.002  # dt <= 1/250 s keeps fingers out of boxes
    control_rate_hz: Annotated[float, Field(gt=0, le=1000)] = 100.0  # behaviour-tree ticks per second
    gravity_m_s2: Vec3 = (0.0, 0.0, -9.81)
    solver_position_iterations: Annotated[int, Field(ge=1, le=255)] = 20
    solver_velocity_iterations: Annotated[int, Field(ge=1, le=255)] = 4


class Table(StrictModel):
    size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat] = (1.0, 1.4, 0.04)  # x, y, thickness
    center_xy_m: tuple[float, float] = (0.35, 0.0)
    color: str | tuple[float, float, float] = "wood"
    friction: NonNegFloat = 0.6


class RobotMount(StrictModel):
    base_xyz_m: Vec3 = (0.0, 0.0, 0.0)
    base_yaw_deg: float = 0.0
    home_q_rad: tuple[float, float, float, float, float, float] = (0.0, -1.9, 1.9, -1.57, -1.57, 0.0)
    gripper_force_n: PositiveFloat = 40.0
    finger_friction: NonNegFloat = 1.0


class EyeToHand(StrictModel):
    position_m: Vec3 = (1.05, 0.0, 0.75)
    look_at_m: Vec3 = (0.45, 0.0, 0.0)
    roll_deg: float = 0.0


class EyeInHand(StrictModel):
    parent_link: str = "tool0"
    xyz_m: Vec3 = (-0.07, 0.0, 0.01)  # optical centre relative to the parent link
    rpy_deg: Vec3 = (0.0, 12.0, 0.0)  # OpenCV optical axes (z forward) relative to the parent link


class DepthNoise(StrictModel):
    """A D435-like stereo depth error model: RMS error = z^2 * subpixel / (focal * baseline)."""

    enabled: bool = True
    baseline_m: PositiveFloat = 0.050
    focal_px: PositiveFloat = 383.0
    subpixel: NonNegFloat = 0.08
    quantum_m: NonNegFloat = 0.001
    min_range_m: NonNegFloat = 0.28
    max_range_m: PositiveFloat = 3.0
    edge_jump_m: PositiveFloat = 0.03  # depth discontinuity that invalidates neighbouring pixels
    edge_dropout: Annotated[float, Field(ge=0, le=1)] = 0.5  # probability an edge pixel reads invalid
    color_sigma: NonNegFloat = 2.0  # colour noise, standard deviation in 8-bit levels


class Camera(StrictModel):
    model: Literal["d435"] = "d435"
    width_px: Annotated[int, Field(gt=0, le=4096)] = 640
    height_px: Annotated[int, Field(gt=0, le=4096)] = 480
    vfov_deg: Annotated[float, Field(gt=1, lt=170)] = 42.0
    near_m: PositiveFloat = 0.05
    far_m: PositiveFloat = 10.0
    mount: Literal["eye-to-hand", "eye-in-hand"] = "eye-to-hand"
    eye_to_hand: EyeToHand = EyeToHand()
    eye_in_hand: EyeInHand = EyeInHand()
    noise: DepthNoise = DepthNoise()


class Light(StrictModel):
    kind: Literal["ambient", "directional", "point"]
    color: Vec3 = (1.0, 1.0, 1.0)
    direction: Vec3 = (0.0, 0.0, -1.0)
    position_m: Vec3 = (0.0, 0.0, 2.0)
    shadow: bool = False


class ObjectPose(StrictModel):
    xy_m: tuple[float, float]
    yaw_deg: float = 0.0


class Randomize(StrictModel):
    x_m: Range = (0.0, 0.0)
    y_m: Range = (0.0, 0.0)
    yaw_deg: Range = (0.0, 0.0)

    @field_validator("x_m", "y_m", "yaw_deg")
    @classmethod
    def _ordered(cls, value: Range) -> Range:
        if value[0] > value[1]:
            raise ValueError("a range is [low, high] with low <= high")
        return value


class SceneObject(StrictModel):
    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_\-]*$")]
    shape: Literal["box", "cylinder", "sphere"]
    size_m: tuple[PositiveFloat, ...]  # box: x y z; cylinder: radius height; sphere: radius
    color: str | tuple[float, float, float]
    mass_kg: PositiveFloat = 0.1
    friction: NonNegFloat = 0.8
    pose: ObjectPose
    randomize: Randomize = Randomize()

    @model_validator(mode="after")
    def _size_matches_shape(self) -> SceneObject:
        expected = {"box": 3, "cylinder": 2, "sphere": 1}[self.shape]
        if len(self.size_m) != expected:
            raise ValueError(f"a {self.shape} needs size_m with {expected} numbers, got {len(self.size_m)}")
        return self

    @field_validator("color")
    @classmethod
    def _known_color(cls, value: str | tuple[float, float, float]) -> str | tuple[float, float, float]:
        if isinstance(value, str) and value not in COLOR_NAMES:
            raise ValueError(f"unknown colour '{value}'; known: {', '.join(COLOR_NAMES)} or [r, g, b] in 0..1")
        if not isinstance(value, str) and not all(0.0 <= c <= 1.0 for c in value):
            raise ValueError("an [r, g, b] colour has components in 0..1")
        return value

    @property
    def height_m(self) -> float:
        return {"box": self.size_m[-1], "cylinder": self.size_m[-1], "sphere": 2 * self.size_m[0]}[self.shape]

    @property
    def rgb(self) -> tuple[float, float, float]:
        return COLOR_NAMES[self.color] if isinstance(self.color, str) else self.color


class Workspace(StrictModel):
    """The region of the table where objects may be (world frame), for perception's region of interest."""

    x_m: Range = (0.25, 0.75)
    y_m: Range = (-0.35, 0.35)
    z_max_m: PositiveFloat = 0.30


class Scene(StrictModel):
    name: str = "scene"
    physics: Physics = Physics()
    table: Table = Table()
    robot: RobotMount = RobotMount()
    camera: Camera = Camera()
    lights: tuple[Light, ...] = (
        Light(kind="ambient", color=(0.45, 0.45, 0.45)),
        Light(kind="directional", direction=(-0.3, 0.2, -1.0), color=(0.8, 0.8, 0.8)),
    )
    workspace: Workspace = Workspace()
    objects: tuple[SceneObject, ...] = ()

    @model_validator(mode="after")
    def _unique_names(self) -> Scene:
        names = [o.name for o in self.objects]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"object names must be unique; repeated: {', '.join(dupes)}")
        return self

    def T_world_base(self) -> np.ndarray:
        """Where the robot is bolted (installation data, known to the pipeline)."""
        yaw = np.deg2rad(self.robot.base_yaw_deg)
        T = np.eye(4)
        T[:3, :3] = [[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]]
        T[:3, 3] = self.robot.base_xyz_m
        return T


def load_scene(path: str | Path) -> Scene:
    """Load and validate a scene file; raises ConfigError naming the file, line and key."""
    return load_model(Scene, path)
