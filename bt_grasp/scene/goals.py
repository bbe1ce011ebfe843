"""The goal a scene declares (``goal:``): what a run on this scene is judged on, by physics.

Kinds (the ``kind`` key selects one)::

    goal: {kind: pick, color: red, height_m: 0.15}                 # an object held >= height_m above the table
    goal: {kind: place, object: red_box, at: target_marker}        # resting on a marker (or at_xy_m: [x, y])
    goal: {kind: stack, object: red_box, on: blue_box}             # resting centred on another object
    goal: {kind: sort, rules: [{color: red, into: left_tray}, {color: blue, into: right_tray}]}
    goal: {kind: clear, into: bin}                                 # every object inside the bin, let go, at rest
    goal: {kind: collect, into: bin, count: 3}                     # at least 3 objects placed into the bin

Placed objects (place, stack, sort, collect) must be released (not touching the fingers), upright within
:data:`UPRIGHT_DEG` (the key ``upright``, true by default: ``upright: false`` leaves it out), still for
:data:`STILL_S` of simulated time after release, and set down, not dropped (fallen less than :data:`MAX_DROP_M`
after the fingers opened). Clearing into a container means what a user clearing a table into a bin means:
every object inside it, released and at rest, whichever way up and however it got there (``upright: true`` and
``set_down: true`` ask for those too). The judge in ``bt_grasp.sim`` checks these with the simulator's ground
truth; the pipeline never reads them.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from bt_grasp.files.config import StrictModel
from bt_grasp.scene.colors import check_color

Name = Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_\-]*$")]
PositiveFloat = Annotated[float, Field(gt=0)]

#: a placed object's tilt from upright may not exceed this
UPRIGHT_DEG = 10.0
#: a placed object must stay still this long (simulated time) after release
STILL_S = 1.0
#: ... moving slower than this (centre speed)
STILL_SPEED_M_S = 0.005
#: a placed object may fall at most this far after the fingers opened (more is a drop)
MAX_DROP_M = 0.01


class PickGoal(StrictModel):
    """An object is held in the gripper at least ``height_m`` above where it started."""

    kind: Literal["pick"]
    object: Name | None = None  # a scene object's name; None: the object the tree lifted
    color: str | None = None  # informs trees that read {color}; the judge checks ``object`` when given
    height_m: PositiveFloat = 0.15


class PlaceGoal(StrictModel):
    """``object`` rests within ``tolerance_m`` of a target: a fixture's centre (``at``) or a point."""

    kind: Literal["place"]
    object: Name
    at: Name | None = None  # a fixture (marker, tray, ...) whose centre is the target
    at_xy_m: tuple[float, float] | None = None  # or a world (x, y) on the table
    tolerance_m: PositiveFloat = 0.01
    upright: bool = True  # it must stand as it stood (tilted at most UPRIGHT_DEG)

    @model_validator(mode="after")
    def _one_target(self) -> PlaceGoal:
        if (self.at is None) == (self.at_xy_m is None):
            raise ValueError("a place goal needs exactly one of 'at' (a fixture name) or 'at_xy_m' ([x, y])")
        return self


class StackGoal(StrictModel):
    """``object`` rests on top of ``on``: centred within ``xy_tolerance_m``, its bottom within
    ``z_tolerance_m`` of the lower object's top (ManiSkill's StackCube: about 3 cm and 5 mm)."""

    kind: Literal["stack"]
    object: Name
    on: Name
    xy_tolerance_m: PositiveFloat = 0.03
    z_tolerance_m: PositiveFloat = 0.005
    upright: bool = True  # the stacked object must stand as it stood (tilted at most UPRIGHT_DEG)


class SortRule(StrictModel):
    color: str
    into: Name  # a tray or bin

    @model_validator(mode="after")
    def _color(self) -> SortRule:
        check_color(self.color)
        return self


class SortGoal(StrictModel):
    """Every object whose colour a rule names is placed inside that rule's container."""

    kind: Literal["sort"]
    rules: Annotated[tuple[SortRule, ...], Field(min_length=1)]
    upright: bool = True  # each object must stand as it stood (tilted at most UPRIGHT_DEG)


class ClearGoal(StrictModel):
    """Every object leaves the work area; with ``into``, each is inside that container, released and at rest
    (``upright``: also standing as it stood; ``set_down``: also set down, not dropped)."""

    kind: Literal["clear"]
    into: Name | None = None
    upright: bool = False
    set_down: bool = False

    @model_validator(mode="after")
    def _placed_keys_need_into(self) -> ClearGoal:
        if (self.upright or self.set_down) and self.into is None:
            raise ValueError("'upright' and 'set_down' judge objects placed into a container: give 'into' too")
        return self


class CollectGoal(StrictModel):
    """At least ``count`` objects are placed inside ``into`` (which ones does not matter: objects a conveyor's feed
    brings keep coming, and those not taken pass by)."""

    kind: Literal["collect"]
    into: Name
    count: Annotated[int, Field(ge=1, le=1000)]  # a feed holds at most 1,000 objects


Goal = Annotated[PickGoal | PlaceGoal | StackGoal | SortGoal | ClearGoal | CollectGoal, Field(discriminator="kind")]
GOAL_KINDS: tuple[str, ...] = ("pick", "place", "stack", "sort", "clear", "collect")
