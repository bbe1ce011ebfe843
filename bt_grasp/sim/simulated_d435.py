"""The simulated cell's D435 as a real one delivers it: the colour imager's picture and the depth imager's own.

``SimCamera`` hands perception depth already aligned to colour. A real D435 (and a recording of one) holds the depth
imager's picture, which pyrealsense2 aligns to colour. :class:`SimulatedD435` gives the raw pair, frame after frame,
with the world stepped one frame period between frames (simulated time only):

* ``color``: ``SimCamera.capture()``'s picture, its noise from the world's camera stream, exactly what a run's
  ``Perceive`` would get at that moment; ``aligned_depth_m`` is that capture's colour-aligned depth, kept for
  comparison (what a run perceives);
* ``depth_m``: the depth imager's picture (:mod:`bt_grasp.sim.depth_imager`), its noise from a stream of its own
  (child 3 of the world's seed sequence; the world spawns children 0-2), so the colour side is unchanged by it;
* ``q_rad``: the arm's measured joints (an eye-in-hand camera's pose comes from them), ``stamp_ns`` simulated time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.seeds import RunSeeds, Stream
from bt_grasp.sim.depth_imager import DepthImager, DepthImagerModel
from bt_grasp.sim.world import World

#: frames per second of the simulated D435's streams
FPS = 30


@dataclass(frozen=True)
class D435Frame:
    """One frame of both imagers at ``stamp_ns`` (simulated time)."""

    color: NDArray[np.uint8]  # (H, W, 3) RGB, the colour imager's
    depth_m: NDArray[np.float32]  # the depth imager's own picture, metres, 0 = invalid
    aligned_depth_m: NDArray[np.float32]  # the simulator's colour-aligned depth of the same moment (what run sees)
    stamp_ns: int
    number: int
    q_rad: NDArray[np.float64]  # the arm's measured joint positions


class SimulatedD435:
    """Frames of both imagers of ``world``'s camera (see the module docstring)."""

    def __init__(self, world: World, model: DepthImagerModel | None = None) -> None:
        self.world = world
        camera = world.config.camera
        self.model = model or DepthImagerModel.d435(camera.width_px, camera.height_px)
        rng = RunSeeds(world.seed).generator(Stream.DEPTH_IMAGER)
        self.imager = DepthImager(world.camera, self.model, camera.noise, rng, camera.near_m, camera.far_m)
        self.steps_per_frame = max(1, round(1.0 / (FPS * world.dt_s)))
        self._number = 0

    def capture(self) -> D435Frame:
        """Both imagers' pictures of the world as it is now."""
        frame = self.world.camera.capture()
        assert frame is not None  # the simulated camera drops frames only through a fault injector
        depth = self.imager.capture()
        out = D435Frame(color=frame.color, depth_m=depth, aligned_depth_m=frame.depth_m, stamp_ns=self.world.now_ns(),
                        number=self._number, q_rad=self.world.robot.joint_positions().copy())
        self._number += 1
        return out

    def next_frame(self) -> None:
        """Let one frame period of simulated time pass."""
        self.world.step(self.steps_per_frame)
