"""Which ways a held object may be turned when it is set down, in the order Place tries them.

An object rests on the same footprint when it is turned about the vertical by one of its footprint's
symmetries: half a turn for a rectangle, a quarter turn for a square, any turn for a round footprint (a
standing can or bottle). When the goal does not care about the object's yaw (``free_yaw``), any turn is
allowed. Turning the object turns the tool with it (the grasp is kept), so each turn is a different place
for the fingers and the arm; Place tries them in order and keeps the first whose release pose is reachable
and whose open fingers, palm and arm clear what was seen and the known fixtures
(``bt_grasp.behaviours.place``).

The order is deterministic: first the one Place always chose (the requested yaw, or half a turn from it,
whichever turns the wrist less from the grasp; the object as held when no yaw is asked), then the others,
smallest wrist turn first, a positive turn before the negative one of the same size.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

#: a footprint is square when its two sides differ by at most this much (or this share of the longer one)
SQUARE_TOLERANCE_M = 0.005
SQUARE_TOLERANCE_SHARE = 0.12
#: the step between turns tried for a round footprint or a free yaw, degrees
FREE_STEP_DEG = 30.0


class FootprintKind(enum.Enum):
    """How the footprint looks from above (what decides its symmetries)."""

    RECTANGLE = "rectangle"
    SQUARE = "square"
    ROUND = "round"


def footprint_kind(length_m: float, width_m: float, round_footprint: bool) -> FootprintKind:
    """``ROUND`` when perception saw a round footprint, ``SQUARE`` when its sides are (nearly) equal, else
    ``RECTANGLE``."""
    if round_footprint:
        return FootprintKind.ROUND
    longer, shorter = max(length_m, width_m), min(length_m, width_m)
    if longer - shorter <= max(SQUARE_TOLERANCE_M, SQUARE_TOLERANCE_SHARE * longer):
        return FootprintKind.SQUARE
    return FootprintKind.RECTANGLE


def footprint_turns_rad(kind: FootprintKind, free_yaw: bool = False) -> tuple[float, ...]:
    """The object turns (about the vertical, radians, in [0, 2 pi)) that leave the footprint where it was."""
    if free_yaw or kind is FootprintKind.ROUND:
        steps = round(360.0 / FREE_STEP_DEG)
        return tuple(math.radians(FREE_STEP_DEG * k) for k in range(steps))
    if kind is FootprintKind.SQUARE:
        return tuple(math.radians(a) for a in (0.0, 90.0, 180.0, 270.0))
    return (0.0, math.pi)


def wrap_rad(angle: float) -> float:
    """The angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


@dataclass(frozen=True)
class PlaceYaw:
    """One way to set the object down: its yaw at rest, and how far the wrist turns from the grasp."""

    object_yaw_rad: float  # the object's yaw at rest, base frame
    turn_rad: float  # the footprint turn this candidate adds to the requested yaw (0: as requested)
    wrist_turn_rad: float  # the tool's turn about the vertical from the grasp, in [-pi, pi)


def place_yaws(requested_yaw_rad: float, held_yaw_rad: float, turns_rad: tuple[float, ...]) -> list[PlaceYaw]:
    """The candidate object yaws in the order to try them (the object's yaw as grasped is ``held_yaw_rad``;
    the tool turns with it). First the requested yaw itself, or half a turn from it, whichever turns the wrist
    less (what Place always chose, so every place that worked before is made the same way); then the other
    turns, smallest wrist turn first, the positive one before the negative one of the same size. The order
    never depends on anything but the arguments."""
    out = [PlaceYaw(requested_yaw_rad + t, t, wrap_rad(requested_yaw_rad + t - held_yaw_rad)) for t in turns_rad]

    def key(c: PlaceYaw) -> tuple[int, float, float]:
        as_requested = abs(wrap_rad(c.turn_rad)) < 1e-9 or abs(abs(wrap_rad(c.turn_rad)) - math.pi) < 1e-9
        return (0 if as_requested else 1, round(abs(c.wrist_turn_rad), 9), -c.wrist_turn_rad)

    ordered = sorted(out, key=key)
    return ordered[:1] + sorted(ordered[1:], key=lambda c: (round(abs(c.wrist_turn_rad), 9), -c.wrist_turn_rad))
