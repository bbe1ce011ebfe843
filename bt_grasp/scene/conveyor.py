"""The conveyor fixture (``fixtures: [{kind: conveyor, ...}]``): a belt that carries objects by friction.

Installation data like every fixture: where it stands (``center_xy_m``, ``yaw_deg``), its size, its belt
speed and direction. The belt runs along the fixture's x axis (``direction: forward`` moves objects
towards +x of the fixture frame); objects whose drawn position lies on the belt start on its surface (the
scene's ``objects`` randomisation says where they enter). The simulator drives the belt as a chain of thin
kinematic slats moving at the belt speed (``bt_grasp.sim.conveyor``): objects ride on them by friction only.

The :data:`bt_grasp.scene.fixtures.Fixture` union includes it.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from bt_grasp.scene.fixture_base import FixtureBase, FixturePart

PositiveFloat = Annotated[float, Field(gt=0)]
#: the fastest belt bt_grasp simulates, m/s: light industrial belts run 0.05-0.5 m/s; faster ones throw
#: objects and need guards this scene model does not have
MAX_BELT_SPEED_M_S = 0.5
#: length of one slat of the simulated belt along the belt, m (the belt's pitch)
SLAT_PITCH_M = 0.05


class Conveyor(FixtureBase):
    """A flat belt conveyor on the table: its top at ``height_m`` above the table top."""

    kind: Literal["conveyor"]
    length_m: Annotated[float, Field(ge=0.2, le=3.0)]  # along the fixture's x axis
    width_m: Annotated[float, Field(ge=0.05, le=1.0)]  # across the belt
    height_m: Annotated[float, Field(ge=0.01, le=0.3)] = 0.03  # belt surface above the table top
    speed_m_s: Annotated[float, Field(ge=0.0, le=MAX_BELT_SPEED_M_S)] = 0.05
    direction: Literal["forward", "backward"] = "forward"
    friction: Annotated[float, Field(ge=0.1, le=2.0)] = 0.8  # belt surface friction coefficient
    color: str | tuple[float, float, float] = "grey"

    @property
    def surface_z_m(self) -> float:
        return float(self.height_m)

    @property
    def belt_velocity_world(self) -> np.ndarray:
        """The belt surface's velocity in the world frame, m/s."""
        sign = 1.0 if self.direction == "forward" else -1.0
        yaw = np.deg2rad(self.yaw_deg)
        return sign * self.speed_m_s * np.array([np.cos(yaw), np.sin(yaw), 0.0])

    def on_belt(self, xy: tuple[float, float] | np.ndarray, margin_m: float = 0.0) -> bool:
        """True when a world point's (x, y) lies over the belt (``margin_m`` inside its edges)."""
        local = np.linalg.inv(self.T_world_fixture()) @ np.array([xy[0], xy[1], 0.0, 1.0])
        return bool(abs(local[0]) <= self.length_m / 2 - margin_m and abs(local[1]) <= self.width_m / 2 - margin_m)

    def parts(self) -> tuple[FixturePart, ...]:
        """The belt's envelope, table to belt surface (what the planner avoids). The simulator builds it as a
        static frame with moving slats on top (``bt_grasp.sim.conveyor``)."""
        h = self.height_m
        return (self._box("belt", (self.length_m, self.width_m, h), (0.0, 0.0, h / 2)),)


#: thickness of the moving slats on top of the frame, m
SLAT_THICKNESS_M = 0.008
