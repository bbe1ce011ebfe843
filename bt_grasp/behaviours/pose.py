"""A pose on the blackboard: position, a yaw about the vertical, and the frame it is written in.

Text form for tree-file ports (BT.CPP style, fields separated by ``;``)::

    "0.35;-0.25"                 x;y              (z and yaw left to the leaf: e.g. the table, any yaw)
    "0.35;-0.25;0.02"            x;y;z
    "0.35;-0.25;0.0;90"          x;y;z;yaw_deg
    "0.35;-0.25;0.0;90;world"    x;y;z;yaw_deg;frame   (frame: base (default) or world)

Metres and degrees. The base frame is the robot's ``base_link``; the world frame has its origin on the table
top, z up (see ``bt_grasp.scene.format``). What the numbers mean is the leaf's: ``Place`` reads the pose of
the held object's centre in x, y, its yaw, and z as the height of the surface it is set on; ``MoveTo`` reads
the tool centre point's position and yaw (the tool always points down).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from bt_grasp.geometry import Mat4, make_T, rot_z

Frame = Literal["base", "world"]
FRAMES: tuple[str, ...] = ("base", "world")


@dataclass(frozen=True)
class Pose:
    x_m: float
    y_m: float
    z_m: float | None = None  # None: the leaf's default (e.g. the table top)
    yaw_deg: float | None = None  # None: the leaf's default (e.g. keep the held object's yaw)
    frame: Frame = "base"

    port_type_name = "a pose 'x;y[;z[;yaw_deg[;frame]]]'"

    def __post_init__(self) -> None:
        numbers = [self.x_m, self.y_m] + [v for v in (self.z_m, self.yaw_deg) if v is not None]
        if not all(math.isfinite(v) for v in numbers):
            raise ValueError(f"a pose's numbers must be finite, got {self.to_port_text()}")
        if self.frame not in FRAMES:
            raise ValueError(f"unknown frame '{self.frame}' (known: {', '.join(FRAMES)})")

    @classmethod
    def from_port_text(cls, text: str) -> Pose:
        """Parse ``x;y[;z[;yaw_deg[;frame]]]``; ValueError with one sentence when malformed."""
        fields = [f.strip() for f in str(text).split(";")]
        if not 2 <= len(fields) <= 5 or any(f == "" for f in fields[:4]):
            raise ValueError(f"expected a pose 'x;y[;z[;yaw_deg[;frame]]]' (metres, degrees), got {text!r}")
        frame = fields[4] if len(fields) == 5 else "base"
        if frame not in FRAMES:
            raise ValueError(f"unknown frame '{frame}' in pose {text!r} (known: {', '.join(FRAMES)})")
        try:
            numbers = [float(f) for f in fields[:4]]
        except ValueError:
            raise ValueError(f"a pose's fields must be numbers (metres, degrees), got {text!r}") from None
        if not all(math.isfinite(v) for v in numbers):
            raise ValueError(f"a pose's numbers must be finite, got {text!r}")
        z = numbers[2] if len(numbers) > 2 else None
        yaw = numbers[3] if len(numbers) > 3 else None
        return cls(numbers[0], numbers[1], z, yaw, frame)  # type: ignore[arg-type]

    def to_port_text(self) -> str:
        parts = [f"{self.x_m:g}", f"{self.y_m:g}"]
        if self.z_m is not None or self.yaw_deg is not None or self.frame != "base":
            parts.append(f"{self.z_m if self.z_m is not None else 0.0:g}")
        if self.yaw_deg is not None or self.frame != "base":
            parts.append(f"{self.yaw_deg if self.yaw_deg is not None else 0.0:g}")
        if self.frame != "base":
            parts.append(self.frame)
        return ";".join(parts)

    def __str__(self) -> str:
        return self.to_port_text()

    def in_base(self, T_world_base: Mat4) -> Pose:
        """The same pose in the base frame (``T_world_base``: where the robot is bolted, installation data)."""
        if self.frame == "base":
            return self
        T_base_world = np.linalg.inv(np.asarray(T_world_base, dtype=float))
        z = self.z_m if self.z_m is not None else 0.0
        p = T_base_world @ np.array([self.x_m, self.y_m, z, 1.0])
        yaw_offset = math.degrees(math.atan2(T_base_world[1, 0], T_base_world[0, 0]))
        return Pose(
            float(p[0]), float(p[1]), float(p[2]) if self.z_m is not None else None,
            None if self.yaw_deg is None else self.yaw_deg + yaw_offset, "base",
        )

    def raised(self, dz_m: float) -> Pose:
        return replace(self, z_m=(self.z_m or 0.0) + dz_m)

    def T(self, default_z_m: float = 0.0, default_yaw_deg: float = 0.0) -> Mat4:
        """A 4x4 transform in the pose's frame (defaults fill an absent z or yaw)."""
        z = self.z_m if self.z_m is not None else default_z_m
        yaw = self.yaw_deg if self.yaw_deg is not None else default_yaw_deg
        return make_T(rot_z(math.radians(yaw)), [self.x_m, self.y_m, z])
