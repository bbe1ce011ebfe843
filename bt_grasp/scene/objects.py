"""The scene's movable objects (``objects:``): what each is, where it is drawn, how its pose is randomised.

Frames: world frame, z up, origin on the table top. An object's drawn pose is the simulator's secret: the
pipeline finds objects with its camera; only the simulator, the judge and tests read these poses.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from bt_grasp.colors import check_color, rgb_of
from bt_grasp.config import StrictModel

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Range = tuple[float, float]


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
        return check_color(value)

    @property
    def height_m(self) -> float:
        return {"box": self.size_m[-1], "cylinder": self.size_m[-1], "sphere": 2 * self.size_m[0]}[self.shape]

    @property
    def rgb(self) -> tuple[float, float, float]:
        return rgb_of(self.color)
