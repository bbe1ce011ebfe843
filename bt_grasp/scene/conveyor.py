"""The conveyor fixture (``fixtures: [{kind: conveyor, ...}]``): a belt that carries objects by friction.

Installation data like every fixture: where it stands (``center_xy_m``, ``yaw_deg``), its size, its belt
speed and direction. The belt runs along the fixture's x axis (``direction: forward`` moves objects
towards +x of the fixture frame); objects whose drawn position lies on the belt start on its surface. The
simulator drives the belt as a chain of thin kinematic slats moving at the belt speed
(``bt_grasp.sim.conveyor``): objects ride on them by friction only.

Two optional parts:

* ``encoder``: the belt has an incremental encoder (as UR's conveyor tracking reads one): ``counts_per_m``. The
  simulator counts the belt's own travel as the encoder on its drive would (``bt_grasp.sim.conveyor``); a run's
  leaves read it through :class:`bt_grasp.interfaces.Encoder`.
* ``feed``: a stream of objects entering at the upstream end: ``count`` objects, each one of ``objects`` (the
  templates, drawn uniformly), set down on the belt ``entry_m`` downstream of its upstream end, ``across_m``
  from its centre line and turned ``yaw_deg``, the first ``first_s`` seconds after the start and each next one
  ``spacing_m`` of belt travel behind the one before (so their times follow from the belt's speed). Every draw
  comes from the run's ``BELT_FEED`` seed stream; an entered object is named ``<template>_<k>`` (k counts the
  entries from 0).

The :data:`bt_grasp.scene.fixtures.Fixture` union includes it.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from bt_grasp.files.config import StrictModel
from bt_grasp.scene.fixture_base import FixtureBase, FixturePart
from bt_grasp.scene.objects import ObjectPose, SceneObject

PositiveFloat = Annotated[float, Field(gt=0)]
Range = tuple[float, float]
#: the fastest belt bt_grasp simulates, m/s: light industrial belts run 0.05-0.5 m/s; faster ones throw
#: objects and need guards this scene model does not have
MAX_BELT_SPEED_M_S = 0.5
#: length of one slat of the simulated belt along the belt, m (the belt's pitch)
SLAT_PITCH_M = 0.05


def _ordered(value: Range, what: str) -> Range:
    if value[0] > value[1]:
        raise ValueError(f"{what} is [low, high] with low <= high")
    return value


class Encoder(StrictModel):
    """The belt's incremental encoder: it counts ``counts_per_m`` per metre of belt travel (its quantisation is
    one count)."""

    counts_per_m: Annotated[float, Field(ge=100, le=1e7)]


class FeedObject(SceneObject):
    """An object template of a feed: a scene object without a pose (the feed draws where it enters)."""

    pose: ObjectPose = ObjectPose(xy_m=(0.0, 0.0))

    @model_validator(mode="after")
    def _no_pose(self) -> FeedObject:
        for key in ("pose", "randomize"):
            if key in self.model_fields_set:
                raise ValueError(f"a feed's object takes no '{key}': the feed draws where it enters")
        return self


class Feed(StrictModel):
    """Objects entering the belt at its upstream end (see the module docstring)."""

    objects: Annotated[tuple[FeedObject, ...], Field(min_length=1)]
    count: Annotated[int, Field(ge=1, le=1000)]
    first_s: Annotated[float, Field(ge=0)] = 0.0  # when the first enters, s after the start
    spacing_m: Range = (0.3, 0.6)  # belt travel between two entries, m (uniform)
    across_m: Range = (0.0, 0.0)  # across the belt, from its centre line (fixture +y), m
    yaw_deg: Range = (-180.0, 180.0)
    entry_m: Annotated[float, Field(ge=0)] = 0.05  # downstream of the upstream end, m

    @field_validator("spacing_m", "across_m", "yaw_deg")
    @classmethod
    def _range(cls, value: Range) -> Range:
        return _ordered(value, "a range")

    @field_validator("spacing_m")
    @classmethod
    def _positive(cls, value: Range) -> Range:
        if value[0] <= 0:
            raise ValueError("spacing_m must be positive: two objects cannot enter at one place")
        return value

    @model_validator(mode="after")
    def _unique(self) -> Feed:
        names = [o.name for o in self.objects]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"a feed's object names must be unique; repeated: {', '.join(dupes)}")
        return self


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
    encoder: Encoder | None = None
    feed: Feed | None = None

    @model_validator(mode="after")
    def _feed_fits(self) -> Conveyor:
        feed = self.feed
        if feed is None:
            return self
        if feed.entry_m >= self.length_m:
            raise ValueError(f"the feed's entry_m ({feed.entry_m} m) is not on the {self.length_m} m belt")
        if max(abs(feed.across_m[0]), abs(feed.across_m[1])) > self.width_m / 2:
            raise ValueError(f"the feed's across_m {list(feed.across_m)} reaches past the belt's edges "
                             f"(+-{self.width_m / 2} m)")
        return self

    @property
    def sign(self) -> float:
        """+1 when objects move towards the fixture's +x, -1 backward."""
        return 1.0 if self.direction == "forward" else -1.0

    @property
    def axis_world(self) -> np.ndarray:
        """The unit vector objects travel along, world frame."""
        yaw = np.deg2rad(self.yaw_deg)
        return self.sign * np.array([np.cos(yaw), np.sin(yaw), 0.0])

    def upstream_end_world(self) -> np.ndarray:
        """The middle of the belt's upstream end, on its surface (world frame)."""
        centre = np.array([self.center_xy_m[0], self.center_xy_m[1], self.surface_z_m])
        return np.asarray(centre - self.axis_world * self.length_m / 2)

    @property
    def surface_z_m(self) -> float:
        return float(self.height_m)

    @property
    def belt_velocity_world(self) -> np.ndarray:
        """The belt surface's velocity in the world frame, m/s."""
        return np.asarray(self.speed_m_s * self.axis_world)

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
