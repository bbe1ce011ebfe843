"""``RealSenseCamera``: the :class:`bt_grasp.interfaces.Camera` of a RealSense device or recording.

One class for a live device and for a recording, as in librealsense itself: both are a started
``pyrealsense2.pipeline``. Each :meth:`RealSenseCamera.capture`

1. waits for a frame set holding a depth and a colour frame neither of which was used before, taken together
   (their device timestamps within half a frame period: the pipeline's syncer also hands out sets that pair a new
   frame with the other stream's previous one); none within ``timeout_ms`` of wall time is a dropped frame (None),
   and so is the end of a recording (known from the playback's status; a file's frames are awaited up to
   :data:`PLAYBACK_TIMEOUT_MS`);
2. runs the depth post-processing filters of the settings (``bt_grasp.hardware.realsense_settings``);
3. aligns depth to colour with the library's own ``rs.align(rs.stream.color)``: depth then lies in the colour
   picture's pixels, with the colour imager's intrinsics, as :class:`bt_grasp.interfaces.RGBDFrame` wants it;
4. returns the frame with the depth picture's device timestamp as ``stamp_ns`` and depth in metres (Z16 times the
   depth sensor's depth scale).

The intrinsics, the depth scale and the colour-depth extrinsics come from the stream profiles. Time: a live device's
frames arrive in wall time, so waiting for one reads the wall clock (the one place bt_grasp decides anything from
it, and only for a live device or a file being read); ``stamp_ns`` is the device's own clock.
"""

from __future__ import annotations

import contextlib
import logging
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.hardware.device_objects import RsObject
from bt_grasp.hardware.realsense_settings import DepthFilter, RealSenseSettings
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame

log = logging.getLogger(__name__)

#: while a recording plays, wait this long at a time, checking between waits whether it ended
_PLAYBACK_POLL_MS = 100
#: a recording is read, not streamed: its next frame comes when the file reader gets to it (not in real time), so
#: its end is known from the playback's status, and only a reader stuck this long counts as a dropped frame (a
#: 1 s limit lost a whole recording's frames once on this 2-core machine shared by several test runs)
PLAYBACK_TIMEOUT_MS = 30_000


@dataclass(frozen=True)
class StreamInfo:
    """What the stream profiles say about the camera: both imagers' intrinsics, how they relate, the depth unit."""

    color: CameraIntrinsics
    depth: CameraIntrinsics
    T_color_depth: Mat4  # depth-imager points -> colour-imager points (librealsense's depth-to-colour extrinsics)
    depth_scale_m: float
    fps: float
    serial: str
    name: str
    color_format: str
    distortion: str  # the colour stream's distortion model and whether its coefficients are all zero


def intrinsics_of(profile: RsObject) -> CameraIntrinsics:
    i = profile.as_video_stream_profile().get_intrinsics()
    return CameraIntrinsics(int(i.width), int(i.height), float(i.fx), float(i.fy), float(i.ppx), float(i.ppy))


def matrix_of(extrinsics: RsObject) -> Mat4:
    """``rs.extrinsics`` (rotation column-major) as a 4x4 transform."""
    T = np.eye(4)
    T[:3, :3] = np.asarray(extrinsics.rotation, dtype=float).reshape(3, 3, order="F")
    T[:3, 3] = np.asarray(extrinsics.translation, dtype=float)
    return T


class RealSenseCamera:
    """Implements :class:`bt_grasp.interfaces.Camera` on a started pipeline (see the module docstring).

    Build one with :func:`bt_grasp.hardware.realsense_open.open_recording` or ``open_device``.
    """

    def __init__(self, rs: RsObject, pipeline: RsObject, profile: RsObject, settings: RealSenseSettings, mount: Mount,
                 source: str, playback: RsObject | None = None) -> None:
        self._rs = rs
        self._pipeline = pipeline
        self._settings = settings
        self._mount = mount
        self.source = source
        self._playback = playback
        color = profile.get_stream(rs.stream.color)
        depth = profile.get_stream(rs.stream.depth)
        device = profile.get_device()
        intr = color.as_video_stream_profile().get_intrinsics()
        zero = all(abs(float(c)) < 1e-12 for c in intr.coeffs)
        self.info = StreamInfo(
            color=intrinsics_of(color), depth=intrinsics_of(depth),
            T_color_depth=matrix_of(depth.get_extrinsics_to(color)),
            depth_scale_m=float(device.first_depth_sensor().get_depth_scale()),
            fps=float(depth.fps()),
            serial=_info(rs, device, rs.camera_info.serial_number),
            name=_info(rs, device, rs.camera_info.name),
            color_format=str(color.format()).removeprefix("format."),
            distortion=f"{str(intr.model).removeprefix('distortion.')}{'' if zero else ' (non-zero coefficients)'}",
        )
        if not zero:
            log.warning("%s: the colour stream has %s distortion; bt_grasp's pinhole model ignores it",
                        source, self.info.distortion)
        self._align = rs.align(rs.stream.color)
        self._filters = self._make_filters(settings.ordered_filters)
        self._half_period_ms = 500.0 / max(self.info.fps, 1e-6)
        self._last_numbers: tuple[int, int] | None = None
        self._ended = False
        self.captures = 0
        self.dropped = 0

    # -- the Camera protocol ---------------------------------------------------------------------------------------

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.info.color

    @property
    def mount(self) -> Mount:
        return self._mount

    def capture(self) -> RGBDFrame | None:
        """The next frame (see the module docstring), or None: nothing arrived within the timeout, or the
        recording ended."""
        pair = self._next_pair()
        if pair is None:
            self.dropped += 1
            return None
        frames, stamp_ns = pair
        for block in self._filters:
            frames = block.process(frames).as_frameset()
        aligned = self._align.process(frames)
        depth_frame, color_frame = aligned.get_depth_frame(), aligned.get_color_frame()
        z16 = np.asanyarray(depth_frame.get_data())
        depth_m = (z16.astype(np.float32) * np.float32(self.info.depth_scale_m)).astype(np.float32)
        color = self._rgb(np.asanyarray(color_frame.get_data()))
        self.captures += 1
        return RGBDFrame(color=color, depth_m=depth_m, intrinsics=self.info.color, stamp_ns=stamp_ns,
                         mount=self._mount)

    # -- frames -------------------------------------------------------------------------------------------------------

    def _next_pair(self) -> tuple[RsObject, int] | None:
        if self._ended:
            return None
        timeout_ms = self._settings.timeout_ms if self._playback is None else max(self._settings.timeout_ms,
                                                                                   PLAYBACK_TIMEOUT_MS)
        deadline = time.monotonic() + timeout_ms / 1000.0
        while True:
            remaining_ms = int((deadline - time.monotonic()) * 1000)
            if remaining_ms <= 0:
                log.info("%s: no frame within %d ms (a dropped frame)", self.source, timeout_ms)
                return None
            wait_ms = min(remaining_ms, _PLAYBACK_POLL_MS) if self._playback is not None else remaining_ms
            ok, frames = self._pipeline.try_wait_for_frames(wait_ms)
            if not ok:
                if self._playback is not None and self._playback.current_status() == self._rs.playback_status.stopped:
                    log.info("%s: the recording ended", self.source)
                    self._ended = True
                    return None
                continue
            depth, color = frames.get_depth_frame(), frames.get_color_frame()
            if not depth or not color:
                continue
            numbers = (int(depth.get_frame_number()), int(color.get_frame_number()))
            last = self._last_numbers
            if last is not None and (numbers[0] == last[0] or numbers[1] == last[1]):
                continue  # the syncer paired a new frame with the other stream's previous one
            if abs(depth.get_timestamp() - color.get_timestamp()) > self._half_period_ms:
                continue
            self._last_numbers = numbers
            return frames, round(depth.get_timestamp() * 1e6)

    def skip(self, count: int) -> int:
        """Read and drop up to ``count`` frame sets (a live device's auto-exposure settling); how many came."""
        came = 0
        for _ in range(count):
            ok, _frames = self._pipeline.try_wait_for_frames(self._settings.timeout_ms)
            if not ok:
                break
            came += 1
        return came

    def _rgb(self, pixels: NDArray[np.uint8]) -> NDArray[np.uint8]:
        fmt = self.info.color_format
        if fmt in ("bgr8", "bgra8"):
            pixels = pixels[..., 2::-1]
        return np.ascontiguousarray(pixels[..., :3], dtype=np.uint8)

    def _make_filters(self, filters: tuple[DepthFilter, ...]) -> list[RsObject]:
        rs = self._rs
        blocks: list[RsObject] = []
        smooth = [f for f in filters if f in (DepthFilter.SPATIAL, DepthFilter.TEMPORAL)]
        if smooth:
            blocks.append(rs.disparity_transform(True))
            blocks.extend(rs.spatial_filter() if f is DepthFilter.SPATIAL else rs.temporal_filter() for f in smooth)
            blocks.append(rs.disparity_transform(False))
        if DepthFilter.HOLE_FILLING in filters:
            blocks.append(rs.hole_filling_filter())
        return blocks

    def close(self) -> None:
        """Stop streaming (idempotent)."""
        if self._pipeline is not None:
            if self._playback is not None:  # no frame in flight while the pipeline stops: librealsense's playback
                with contextlib.suppress(RuntimeError):  # sensor can race its callback at stop (librealsense #9446;
                    self._playback.pause()  # one abort seen here in a 2-worker test run under load 25)
            with contextlib.suppress(RuntimeError):  # stopped already (a device unplugged)
                self._pipeline.stop()
            self._pipeline = None
            self._playback = None
            self._filters = []  # the processing blocks go with the pipeline that fed them
            self._ended = True

    def __enter__(self) -> RealSenseCamera:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _info(rs: RsObject, device: RsObject, key: RsObject) -> str:
    return str(device.get_info(key)) if device.supports(key) else ""


#: colour formats a camera may stream that bt_grasp reads (RGB, BGR, with or without alpha)
COLOR_FORMATS = ("rgb8", "bgr8", "rgba8", "bgra8")
