"""Default values that the command line shows in its help, kept in a leaf module so that printing help imports
nothing else (``bt_grasp.episode.request`` re-exports them under the same names)."""

from __future__ import annotations

#: the pick goal's default lift height, metres
DEFAULT_LIFT_HEIGHT_M = 0.15

#: an episode's default tick limit: 120 s of simulated time at 100 Hz
DEFAULT_MAX_TICKS = 12000

#: how long after a frame's timestamp its detections reach the tree in a simulated run, s (a scene's
#: ``perception_latency_s`` overrides it): this pipeline's median capture-to-detections time on the project's
#: 2-core machine plus a D435's own frame delay (the measurement is in docs/perception.md, "Perception latency")
DEFAULT_PERCEPTION_LATENCY_S = 0.100
