"""Default values that the command line shows in its help, kept in a leaf module so that printing help imports
nothing else (``bt_grasp.episode.request`` re-exports them under the same names)."""

from __future__ import annotations

#: the pick goal's default lift height, metres
DEFAULT_LIFT_HEIGHT_M = 0.15

#: an episode's default tick limit: 120 s of simulated time at 100 Hz
DEFAULT_MAX_TICKS = 12000
