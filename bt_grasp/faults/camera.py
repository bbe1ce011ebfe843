"""A camera wrapper whose captures a fault can drop, blank in a rectangle or drown in depth noise."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from bt_grasp.faults.armed import ArmedFault
from bt_grasp.interfaces import Camera, CameraIntrinsics, Mount, RGBDFrame

#: changes a frame (or drops it: returns None) and says what it did
FrameEffect = Callable[[RGBDFrame], tuple[RGBDFrame | None, dict[str, object]]]


@dataclasses.dataclass
class _Active:
    arming: ArmedFault
    effect: FrameEffect | None  # None: no frame at all
    frames_left: int | None  # None: until the arming is finished by its owner (a timed hang)


class FaultyCamera:
    """Implements :class:`bt_grasp.interfaces.Camera` around the real one; passes frames through unless armed."""

    def __init__(self, inner: Camera) -> None:
        self.inner = inner
        self._active: list[_Active] = []

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.inner.intrinsics

    @property
    def mount(self) -> Mount:
        return self.inner.mount

    def add(self, arming: ArmedFault, effect: FrameEffect | None, frames: int | None) -> None:
        """Apply ``effect`` (None: drop the frame) to the next ``frames`` captures (None: until finished)."""
        self._active.append(_Active(arming, effect, frames))

    def capture(self) -> RGBDFrame | None:
        self._active = [a for a in self._active if not a.arming.done]
        if not self._active:
            return self.inner.capture()
        dropping = [a for a in self._active if a.effect is None]
        frame: RGBDFrame | None = None
        if dropping:
            for a in dropping:
                a.arming.fire(effect="no frame")
        else:
            frame = self.inner.capture()
            for a in self._active:
                if frame is None:
                    break
                assert a.effect is not None
                frame, details = a.effect(frame)
                a.arming.fire(**details)
        for a in dropping if dropping else self._active:
            if a.frames_left is not None:
                a.frames_left -= 1
                if a.frames_left <= 0:
                    a.arming.finish()
        return frame


def depth_hole(u_px: int, v_px: int, width_px: int, height_px: int) -> FrameEffect:
    """Depth reads 0 (invalid) in the rectangle (clipped to the image), as over a specular or black surface."""

    def apply(frame: RGBDFrame) -> tuple[RGBDFrame | None, dict[str, object]]:
        depth = frame.depth_m.copy()
        h, w = depth.shape
        u0, v0 = min(u_px, w), min(v_px, h)
        u1, v1 = min(u_px + width_px, w), min(v_px + height_px, h)
        depth[v0:v1, u0:u1] = 0.0
        return dataclasses.replace(frame, depth_m=depth), {"hole_px": [u0, v0, u1 - u0, v1 - v0]}

    return apply


def depth_burst(sigma_m: float, fraction: float, rng: np.random.Generator) -> FrameEffect:
    """Heavy Gaussian noise on a share of the valid depth pixels (interference, an IR projector glitch)."""

    def apply(frame: RGBDFrame) -> tuple[RGBDFrame | None, dict[str, object]]:
        depth = frame.depth_m.copy()
        hit = (depth > 0) & (rng.random(depth.shape) < fraction)
        noise = rng.standard_normal(int(hit.sum())).astype(np.float32) * np.float32(sigma_m)
        depth[hit] = np.maximum(depth[hit] + noise, 0.0)
        return dataclasses.replace(frame, depth_m=depth), {"pixels_hit": int(hit.sum()), "sigma_m": sigma_m}

    return apply
