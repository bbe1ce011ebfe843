"""Was an object placed, by physics? The judge's tracker of releases and its placement conditions.

:class:`PlacementTracker` watches every object once per tick (ground truth, judge only): while both finger
pads touch it, it is held; the tick contact stops is its release, and its centre's height then is kept.
At the end of a run an object counts as *placed* when it is (``bt_grasp.scene.goals`` holds the numbers):

- released: no finger touches it;
- upright: its z axis within ``UPRIGHT_DEG`` of vertical;
- resting: its centre slower than ``STILL_SPEED_M_S`` for the last ``STILL_S`` of simulated time, and
  released at least that long ago;
- set down, not dropped: its centre fell less than ``MAX_DROP_M`` after the release.

Where it must be (a point, on another object, inside a container) is each goal kind's own condition.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_grasp.scene.goals import MAX_DROP_M, STILL_S, STILL_SPEED_M_S, UPRIGHT_DEG
from bt_grasp.sim.oracle import GroundTruthOracle


@dataclass
class _Track:
    held: bool = False
    released_s: float | None = None  # when contact with the fingers last ended
    z_at_release_m: float | None = None
    moving_s: float = 0.0  # the last time it moved faster than STILL_SPEED_M_S


@dataclass(frozen=True)
class Placement:
    """What the judge measured about one object at the end of a run."""

    name: str
    xyz_m: tuple[float, float, float]  # centre, world frame
    tilt_deg: float
    touching_fingers: bool
    released: bool  # was held at some point and is not now
    still_for_s: float
    fall_after_release_m: float | None

    @property
    def upright(self) -> bool:
        return self.tilt_deg <= UPRIGHT_DEG

    @property
    def resting(self) -> bool:
        return self.still_for_s >= STILL_S - 1e-9

    @property
    def set_down(self) -> bool:
        return self.fall_after_release_m is not None and self.fall_after_release_m < MAX_DROP_M

    def measured(self) -> dict[str, str]:
        """Criterion value -> what was measured, for a verdict's details."""
        fall_m = self.fall_after_release_m
        fall_mm = None if fall_m is None else round(fall_m * 1000)  # an int: never "-0"
        fall = ("was never released" if fall_mm is None else f"rose {-fall_mm} mm after release" if fall_mm < 0
                else f"fell {fall_mm} mm after release")
        return {
            "released": f"{self.name} {'touches a finger' if self.touching_fingers else 'free of the fingers'}",
            "upright": f"{self.name} tilts {self.tilt_deg:.1f} deg",
            "resting": f"{self.name} still {self.still_for_s:.1f} s",
            "set_down": f"{self.name} {fall}",
        }

    def problems(self) -> list[tuple[str, str]]:
        """(criterion value, detail) for every placement condition this object misses."""
        out = []
        if not self.released or self.touching_fingers:
            out.append(("released", f"{self.name} " + ("is still touching the fingers" if self.touching_fingers
                                                       else "was never picked up and let go")))
        if not self.upright:
            out.append(("upright", f"{self.name} tilts {self.tilt_deg:.0f} deg (at most {UPRIGHT_DEG:.0f})"))
        if not self.resting:
            out.append(("resting", f"{self.name} still for only {self.still_for_s:.2f} s of {STILL_S:.1f} s"))
        if self.released and not self.set_down:
            fall = self.fall_after_release_m or 0.0
            out.append(("set_down", f"{self.name} fell {fall * 100:.1f} cm after release (dropped: "
                                    f">= {MAX_DROP_M * 100:.0f} cm)"))
        return out


@dataclass
class PlacementTracker:
    oracle: GroundTruthOracle
    tracks: dict[str, _Track] = field(default_factory=dict)

    def observe(self, now_s: float) -> None:
        """Once per tick: who is held, who was just released, who moves."""
        for name in self.oracle.object_names():
            track = self.tracks.setdefault(name, _Track(moving_s=now_s))
            held = self.oracle.object_in_gripper(name)
            if track.held and not held:
                track.released_s = now_s
                track.z_at_release_m = float(self.oracle.T_world_object(name)[2, 3])
            track.held = held
            if float(np.linalg.norm(self.oracle.object_velocity(name))) > STILL_SPEED_M_S:
                track.moving_s = now_s

    def settle_s(self, now_s: float) -> float:
        """How much longer the world must run so every released object can show it rests for STILL_S."""
        releases = [t.released_s for t in self.tracks.values() if t.released_s is not None]
        return max(0.0, STILL_S - (now_s - max(releases))) if releases else 0.0

    def placement(self, name: str, now_s: float) -> Placement:
        track = self.tracks.get(name, _Track(moving_s=now_s))
        T = self.oracle.T_world_object(name)
        tilt = math.degrees(math.acos(float(np.clip(T[2, 2], -1.0, 1.0))))
        released = track.released_s is not None and not track.held
        since = now_s - max(track.moving_s, track.released_s if track.released_s is not None else -math.inf)
        fall = None if track.z_at_release_m is None else track.z_at_release_m - float(T[2, 3])
        return Placement(name, (float(T[0, 3]), float(T[1, 3]), float(T[2, 3])), tilt,
                         self.oracle.object_touches_fingers(name), released, max(0.0, since), fall)
