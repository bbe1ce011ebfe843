"""What every fixture kind shares: a name, a footprint centre and yaw on the table, a colour, and its
description as boxes (:class:`FixturePart`). The kinds themselves are in :mod:`bt_grasp.scene.fixtures`
(and the conveyor in :mod:`bt_grasp.scene.conveyor`); this module imports neither.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

import numpy as np
from pydantic import Field, field_validator

from bt_grasp.files.config import StrictModel
from bt_grasp.geometry import Mat4, make_T, rot_z
from bt_grasp.scene.colors import RGB, check_color, rgb_of

PositiveFloat = Annotated[float, Field(gt=0)]
Name = Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_\-]*$")]

@dataclass(frozen=True)
class FixturePart:
    """One box of a fixture: full edge lengths along its axes, its pose in the world frame."""

    name: str
    size_m: tuple[float, float, float]
    T_world_part: Mat4
    solid: bool = True  # False: paint (a marker), no collision and no planning obstacle
    rgb: RGB = (0.5, 0.5, 0.5)


class FixtureBase(StrictModel):
    name: Name
    center_xy_m: tuple[float, float]
    yaw_deg: float = 0.0
    color: str | RGB = "grey"

    @field_validator("color")
    @classmethod
    def _known_color(cls, value: str | RGB) -> str | RGB:
        return check_color(value)

    @property
    def rgb(self) -> RGB:
        return rgb_of(self.color)

    def T_world_fixture(self, z_m: float = 0.0) -> Mat4:
        """The fixture's frame: centre of its footprint on the table top, yawed."""
        return make_T(rot_z(np.deg2rad(self.yaw_deg)), [self.center_xy_m[0], self.center_xy_m[1], z_m])

    def _box(self, name: str, size: tuple[float, float, float], xyz: tuple[float, float, float],
             solid: bool = True) -> FixturePart:
        T = self.T_world_fixture() @ make_T(translation=list(xyz))
        return FixturePart(f"{self.name}/{name}", size, T, solid, self.rgb)
