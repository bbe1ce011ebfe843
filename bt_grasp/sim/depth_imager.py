"""The simulated D435's depth imager: depth rendered from its own viewpoint, with its own intrinsics.

A real D435 measures depth in the frame of its left infrared imager, about 15 mm beside the colour imager and
with a wider field of view (640x480 depth: fx = fy ~ 383 px, 87 x 58 degrees of the 16:10 sensor cropped to 4:3).
``SimCamera`` hands perception depth already in the colour imager's grid (what ``rs.align`` makes of a real
frame); a recording of a real camera holds the depth imager's own picture, and the colour-depth extrinsics
beside it. :class:`DepthImager` renders that picture, so a recording written from the simulator is aligned by
pyrealsense2's own ``align`` exactly as a real camera's is.

Conventions (librealsense's): ``T_color_depth`` maps points of the depth imager's optical frame into the colour
imager's (``rs.extrinsics`` from depth to colour: ``p_color = R p_depth + t``); both optical frames have OpenCV's
axes. The noise of the depth picture is the scene's D435 model (``bt_grasp.sim.noise``), drawn from a stream of
its own (``rng``) so the colour camera's pictures and noise stay exactly what ``SimCamera.capture`` gives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.scene.format import DepthNoise
from bt_grasp.sim.camera import SimCamera
from bt_grasp.sim.noise import apply_depth_noise
from bt_grasp.sim.poses import cv_from_sapien_cam, sapien_cam_from_cv, to_pose, to_T
from bt_grasp.sim.shader_pack import SHADER_DIR

#: the D435's depth imager at 640x480 (Intel's D400 datasheet: 87 x 58 degrees at 16:10; the 4:3 mode keeps
#: the focal length, fx = fy = 383 px at 640 px wide, the value the noise model's ``focal_px`` already uses)
D435_DEPTH_FOCAL_PX = 383.0
#: the colour imager sits this far beside the depth (left infrared) imager: the depth imager's origin in the
#: colour optical frame, m (librealsense reports ~(0.015, 0.000, 0.000) from depth to colour on D435 units)
D435_DEPTH_TO_COLOR_M = (0.015, 0.0, 0.0)


@dataclass(frozen=True)
class DepthImagerModel:
    """The depth imager's intrinsics and its pose in the colour optical frame (``T_color_depth``)."""

    intrinsics: CameraIntrinsics
    T_color_depth: Mat4

    @classmethod
    def d435(cls, width_px: int, height_px: int) -> DepthImagerModel:
        """The D435's nominal depth imager at the colour picture's size (a 4:3 picture of 640x480 by default)."""
        focal = D435_DEPTH_FOCAL_PX * width_px / 640.0
        intrinsics = CameraIntrinsics(width_px, height_px, focal, focal, (width_px - 1) / 2.0, (height_px - 1) / 2.0)
        T = np.eye(4)
        T[:3, 3] = D435_DEPTH_TO_COLOR_M
        return cls(intrinsics, T)


class DepthImager:
    """A second SAPIEN camera on the colour camera's parent, at ``model.T_color_depth``, drawing depth only."""

    def __init__(self, color: SimCamera, model: DepthImagerModel, noise: DepthNoise, rng: np.random.Generator,
                 near_m: float, far_m: float) -> None:
        self.model = model
        self._noise = noise
        self._rng = rng
        i = model.intrinsics
        parent = color._component  # the colour imager's own render component: the depth imager rides with it
        self._scene = color._scene
        self._component = sapien.render.RenderCameraComponent(i.width_px, i.height_px, SHADER_DIR)
        # SAPIEN's principal point has pixel centres at half-integers: OpenCV's cx + 0.5 (sim/camera.py)
        self._component.set_perspective_parameters(near_m, far_m, i.fx_px, i.fy_px, i.cx_px + 0.5, i.cy_px + 0.5,
                                                   0.0)
        T_parent_color_cv = cv_from_sapien_cam(to_T(parent.get_local_pose()))
        T_parent_depth_cv = T_parent_color_cv @ model.T_color_depth
        self._component.set_local_pose(to_pose(sapien_cam_from_cv(T_parent_depth_cv)))
        parent.entity.add_component(self._component)

    def render_true(self) -> NDArray[np.float32]:
        """Noise-free depth along the depth imager's optical axis, m (0 where nothing was hit)."""
        self._scene.update_render()
        self._component.take_picture()
        position = self._component.get_picture("Position")
        depth: NDArray[np.float32] = (-position[..., 2]).astype(np.float32)
        depth[position[..., 3] >= 1.0] = 0.0
        depth[depth < 0] = 0.0
        return depth

    def capture(self) -> NDArray[np.float32]:
        """The depth imager's picture through the scene's D435 noise model (0 = invalid), m."""
        return apply_depth_noise(self.render_true(), self._noise, self._rng)
