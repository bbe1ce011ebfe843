"""Static fixtures a scene file may declare (``fixtures:``): trays, bins, flat markers, walls.

A fixture is installation data, like the table: the robot knows where it is from the scene file (the
planner avoids its solid parts, a tree can ask for its pose with ``FixturePose``); nothing about it is
drawn from the seed. Frames: world frame, z up, origin on the table top.

Every kind is a frozen model with a ``kind`` tag and one method, :meth:`parts`, which describes the
fixture as boxes in the world frame. The simulator builds those boxes (solid ones collide, flat ones are
paint), and the planning scene adds the solid ones as obstacles. **Adding a kind** (e.g. a conveyor):

1. write a model on :class:`~bt_grasp.scene.fixture_base.FixtureBase` (here, or in its own module as the
   conveyor is) with ``kind: Literal["conveyor"]``, a ``name`` and a ``parts()`` method;
2. add it to the :data:`Fixture` union below (the file format then accepts it, with strict key checks);
3. if it is not made of static boxes (a moving belt), register a builder for its kind in
   ``bt_grasp.sim.fixtures.BUILDERS``; otherwise nothing else is needed.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from bt_grasp.scene.conveyor import Conveyor
from bt_grasp.scene.fixture_base import FixtureBase, FixturePart

PositiveFloat = Annotated[float, Field(gt=0)]


class Container(FixtureBase):
    """A floor plate with four walls; ``inner_size_m`` is the free floor inside the walls (x, y)."""

    inner_size_m: tuple[PositiveFloat, PositiveFloat]
    wall_height_m: PositiveFloat = 0.03
    wall_thickness_m: PositiveFloat = 0.01
    floor_thickness_m: PositiveFloat = 0.004

    @property
    def surface_z_m(self) -> float:
        """Height of the floor's top above the table: where a placed object's bottom rests."""
        return self.floor_thickness_m

    def contains_xy(self, xy: tuple[float, float] | np.ndarray, margin_m: float = 0.0) -> bool:
        """True when a world point's (x, y) lies inside the walls, ``margin_m`` away from them."""
        local = np.linalg.inv(self.T_world_fixture()) @ np.array([xy[0], xy[1], 0.0, 1.0])
        hx, hy = self.inner_size_m[0] / 2 - margin_m, self.inner_size_m[1] / 2 - margin_m
        return bool(abs(local[0]) <= hx and abs(local[1]) <= hy)

    def parts(self) -> tuple[FixturePart, ...]:
        ix, iy = self.inner_size_m
        t, h, f = self.wall_thickness_m, self.wall_height_m, self.floor_thickness_m
        ox, oy = ix + 2 * t, iy + 2 * t
        return (
            self._box("floor", (ox, oy, f), (0.0, 0.0, f / 2)),
            self._box("wall_x_minus", (t, oy, h), (-(ix + t) / 2, 0.0, h / 2)),
            self._box("wall_x_plus", (t, oy, h), ((ix + t) / 2, 0.0, h / 2)),
            self._box("wall_y_minus", (ix, t, h), (0.0, -(iy + t) / 2, h / 2)),
            self._box("wall_y_plus", (ix, t, h), (0.0, (iy + t) / 2, h / 2)),
        )


class Tray(Container):
    """A shallow container objects are placed into (walls 3 cm by default)."""

    kind: Literal["tray"]


class Bin(Container):
    """A deeper container (walls 5 cm by default: the gripper's palm, 4 cm above the tool point, must clear
    them when it sets a small object down near a wall)."""

    kind: Literal["bin"]
    wall_height_m: PositiveFloat = 0.05


class Marker(FixtureBase):
    """A flat coloured patch painted on the table (1 mm thick, no collision): a visible place target."""

    kind: Literal["marker"]
    size_m: tuple[PositiveFloat, PositiveFloat] = (0.06, 0.06)

    @property
    def surface_z_m(self) -> float:
        return 0.0

    def parts(self) -> tuple[FixturePart, ...]:
        return (self._box("patch", (self.size_m[0], self.size_m[1], 0.001), (0.0, 0.0, 0.0005), solid=False),)


class Wall(FixtureBase):
    """A solid upright slab standing on the table (``size_m``: x, y, height)."""

    kind: Literal["wall"]
    size_m: tuple[PositiveFloat, PositiveFloat, PositiveFloat]

    @property
    def surface_z_m(self) -> float:
        return float(self.size_m[2])

    def parts(self) -> tuple[FixturePart, ...]:
        x, y, z = self.size_m
        return (self._box("slab", (x, y, z), (0.0, 0.0, z / 2)),)


#: what ``fixtures:`` entries may be; the ``kind`` key selects the model
Fixture = Annotated[Tray | Bin | Marker | Wall | Conveyor, Field(discriminator="kind")]
FIXTURE_KINDS: tuple[str, ...] = ("tray", "bin", "marker", "wall", "conveyor")
CONTAINER_KINDS: tuple[str, ...] = ("tray", "bin")
