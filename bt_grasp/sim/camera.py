"""The simulated RealSense D435: aligned 640x480 colour + depth with a seeded noise model.

Intrinsics: square pixels with the D435 colour imager's vertical field of view (about 42 degrees). The
often-quoted 69 x 42 degrees is the 16:9 mode; a 4:3 640x480 frame of the same sensor is about 55 x 42.
SAPIEN's principal point is (W/2, H/2) in its convention; OpenCV's convention puts pixel centres at
integers, so the OpenCV intrinsics use ((W-1)/2, (H-1)/2).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import sapien
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, T_from_xyz_rpy
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.scene.format import Camera as CameraConfig
from bt_grasp.scene.format import DepthNoise
from bt_grasp.sim.noise import apply_color_noise, apply_depth_noise
from bt_grasp.sim.poses import cv_from_sapien_cam, look_at_cv, sapien_cam_from_cv, to_pose, to_T
from bt_grasp.sim.shader_pack import SHADER_DIR


class PendingPicture:
    """A colour picture handed to the renderer, read back at the first :meth:`result` on the caller's thread.

    The renderer (lavapipe's threads, or a GPU) draws it meanwhile; reading it back later costs only the copy
    (~1.5 ms at 640x480), while waiting for it holds the GIL (SAPIEN's ``get_picture``), so a helper thread
    reading it back would stall the tick loop instead.
    """

    def __init__(self, camera: SimCamera, component: sapien.render.RenderCameraComponent) -> None:
        self._camera = camera
        self._component: sapien.render.RenderCameraComponent | None = component
        self._color: NDArray[np.uint8] | None = None

    def done(self) -> bool:
        """Whether the picture was read back already (then :meth:`result` costs nothing)."""
        return self._color is not None

    def result(self) -> NDArray[np.uint8]:
        if self._color is None:
            assert self._component is not None
            self._color = SimCamera._read_color(self._component)
            self._component = None
            if self._camera._in_flight is self:
                self._camera._in_flight = None
        return self._color


class SimCamera:
    """Implements :class:`bt_grasp.interfaces.Camera`."""

    def __init__(
        self,
        scene: sapien.Scene,
        config: CameraConfig,
        mount: str,
        rng: np.random.Generator,
        now_ns: Callable[[], int],
        parent_link: sapien.physx.PhysxArticulationLinkComponent | None = None,
    ) -> None:
        self._scene = scene
        self._config = config
        self._mount = Mount(mount)
        self._rng = rng
        self._now_ns = now_ns
        w, h = config.width_px, config.height_px
        self._component = sapien.render.RenderCameraComponent(w, h, SHADER_DIR)
        self._component.set_fovy(np.deg2rad(config.vfov_deg), compute_x=True)
        self._component.near = config.near_m
        self._component.far = config.far_m
        if mount == Mount.EYE_TO_HAND:
            e2h = config.eye_to_hand
            T_world_cv = look_at_cv(np.array(e2h.position_m), np.array(e2h.look_at_m), np.deg2rad(e2h.roll_deg))
            entity = sapien.Entity()
            entity.set_name("camera_eye_to_hand")
            entity.add_component(self._component)
            entity.set_pose(to_pose(sapien_cam_from_cv(T_world_cv)))
            scene.add_entity(entity)
        elif mount == Mount.EYE_IN_HAND:
            if parent_link is None:
                raise ValueError("an eye-in-hand camera needs the link it is mounted on")
            eih = config.eye_in_hand
            T_link_cv = T_from_xyz_rpy(np.array(eih.xyz_m), np.deg2rad(eih.rpy_deg))
            self._component.set_local_pose(to_pose(sapien_cam_from_cv(T_link_cv)))
            parent_link.entity.add_component(self._component)
        else:
            raise ValueError(f"unknown camera mount {mount!r}")
        K = self._component.get_intrinsic_matrix()
        self._intrinsics = CameraIntrinsics(
            width_px=w,
            height_px=h,
            fx_px=float(K[0, 0]),
            fy_px=float(K[1, 1]),
            cx_px=(w - 1) / 2.0,
            cy_px=(h - 1) / 2.0,
        )
        self.captures = 0
        self._in_flight: PendingPicture | None = None
        self._log_component: sapien.render.RenderCameraComponent | None = None

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self._intrinsics

    @property
    def mount(self) -> Mount:
        return self._mount

    def _settle(self) -> None:
        """Read back a picture still with the renderer first: one render at a time."""
        pending, self._in_flight = self._in_flight, None
        if pending is not None:
            pending.result()  # kept in the handle for its owner

    def render_true(self) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """Noise-free colour and depth (0 where nothing was hit). Deterministic for a given scene state."""
        self._settle()
        self._scene.update_render()
        self._component.take_picture()
        rgba = self._component.get_picture("Color")
        color = np.clip(np.round(rgba[..., :3] * 255.0), 0, 255).astype(np.uint8)
        position = self._component.get_picture("Position")
        depth = (-position[..., 2]).astype(np.float32)
        depth[position[..., 3] >= 1.0] = 0.0
        depth[depth < 0] = 0.0
        return color, depth

    def _log_camera(self) -> sapien.render.RenderCameraComponent:
        """A second camera at the same place with the same intrinsics and shader pack and 8-bit colour, made on
        first use: the log's colour-only frames."""
        if self._log_component is None:
            w, h = self._intrinsics.width_px, self._intrinsics.height_px
            # 8-bit colour straight from the renderer: the same values as rounding the float picture (checked:
            # identical at 640x480), without reading back and converting 16 bytes a pixel. The format is a global
            # setting read when a camera is made: restored at once, so the pipeline's cameras keep float colour.
            sapien.render.set_picture_format("Color", "r8g8b8a8unorm")
            try:
                log_camera = sapien.render.RenderCameraComponent(w, h, SHADER_DIR)
            finally:
                sapien.render.set_picture_format("Color", "r32g32b32a32sfloat")
            log_camera.set_fovy(self._component.fovy, compute_x=True)
            log_camera.near, log_camera.far = self._component.near, self._component.far
            log_camera.set_local_pose(self._component.get_local_pose())
            self._component.entity.add_component(log_camera)
            self._log_component = log_camera
        return self._log_component

    def render_color(self, fast_shader: bool = True) -> NDArray[np.uint8]:
        """Noise-free colour only (no depth read back): the log's extra frames. Steps nothing, draws nothing.

        ``fast_shader``: through the second camera, which hands back 8-bit colour (no float read-back and
        conversion); False: through the pipeline's camera. Both draw with bt_grasp's shader pack.
        """
        return self.render_color_async(fast_shader).result()

    def render_color_async(self, fast_shader: bool = True) -> PendingPicture:
        """:meth:`render_color` of the scene as it is now, drawn by the renderer while the caller goes on.

        The scene's state is handed to the renderer here (``update_render`` + ``take_picture``); the picture is
        read back at the handle's first ``result()`` (best a few ticks later, when the renderer is done), so the
        world may step meanwhile: the picture is the state at this call (tested against :meth:`render_color`).
        Any later render of this camera first reads it back. Steps nothing, draws nothing.
        """
        self._settle()
        camera = self._log_camera() if fast_shader else self._component
        self._scene.update_render()
        camera.take_picture()
        pending = PendingPicture(self, camera)
        self._in_flight = pending
        return pending

    @staticmethod
    def _read_color(camera: sapien.render.RenderCameraComponent) -> NDArray[np.uint8]:
        rgba = camera.get_picture("Color")
        if rgba.dtype == np.uint8:  # the log camera's 8-bit colour
            return np.ascontiguousarray(rgba[..., :3])
        rgb: NDArray[np.uint8] = np.clip(np.round(rgba[..., :3] * 255.0), 0, 255).astype(np.uint8)
        return rgb

    def capture(self) -> RGBDFrame | None:
        color, depth = self.render_true()
        noise = self._config.noise
        depth = apply_depth_noise(depth, noise, self._rng)
        color = apply_color_noise(color, noise, self._rng)
        self.captures += 1
        return RGBDFrame(
            color=color, depth_m=depth, intrinsics=self._intrinsics, stamp_ns=self._now_ns(), mount=self._mount
        )

    def capture_variants(self, noises: Sequence[DepthNoise], seed: int) -> list[RGBDFrame]:
        """One rendering of the scene as it is, seen through each noise model (for the noise sweep benchmark:
        the same scene at several sensor qualities). Each variant's noise draws come from ``[seed, k]``."""
        color, depth = self.render_true()
        frames = []
        for k, noise in enumerate(noises):
            rng = np.random.default_rng([seed, k])
            frames.append(RGBDFrame(
                color=apply_color_noise(color, noise, rng), depth_m=apply_depth_noise(depth, noise, rng),
                intrinsics=self._intrinsics, stamp_ns=self._now_ns(), mount=self._mount,
            ))
        return frames

    def true_T_world_cv(self) -> Mat4:
        """The camera's true optical-frame pose. Ground truth: only the oracle may call this."""
        return cv_from_sapien_cam(to_T(self._component.get_global_pose()))
