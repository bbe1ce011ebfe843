"""A ``pyrealsense2.software_device`` shaped like a D435: a depth sensor and a colour sensor, fed from numpy.

The device carries what a real D435 reports: a Z16 depth stream with the depth imager's own intrinsics and a read-only
``depth_units`` option, an RGB8 colour stream with the colour imager's intrinsics, and the extrinsics from depth to
colour registered between the two stream profiles, so ``rs.align`` maps depth onto colour as it does for a real
camera. Frames pushed into it (:meth:`SoftwareD435.push`) are

* written by pyrealsense2's own recorder (:meth:`SoftwareD435.record`): a ``.db3`` recording laid out as the
  RealSense Viewer's, read back by the code that reads every recording; or
* read as a live device (:meth:`SoftwareD435.add_to`): the pipeline finds it by serial number in the context.

pyrealsense2 2.59 keeps only a weak reference to a software device's description in the context it is added to
(``context::query_devices`` then lists nothing, and ``pipeline.start`` says "No device connected"); the context's
devices-changed notification hands a device list that holds it, which :meth:`add_to` keeps for the device's life.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4
from bt_grasp.hardware.device_objects import RsObject
from bt_grasp.hardware.realsense_lib import pyrealsense2
from bt_grasp.interfaces import CameraIntrinsics

log = logging.getLogger(__name__)

#: what a software D435 says it is (``rs.camera_info.name``); a recording keeps it
SIMULATED_NAME = "Intel RealSense D435 (bt_grasp simulated)"
_DEPTH_UID, _COLOR_UID = 0, 1


@dataclass(frozen=True)
class D435Streams:
    """The two streams of a (simulated) D435 and how they relate.

    ``T_color_depth`` maps depth-imager optical-frame points into the colour imager's (librealsense's extrinsics
    from depth to colour); ``depth_unit_m`` is the size of one Z16 step (the D435's default, 1 mm).
    """

    color: CameraIntrinsics
    depth: CameraIntrinsics
    T_color_depth: Mat4
    fps: int = 30
    depth_unit_m: float = 0.001
    serial: str = "000000000000"
    name: str = SIMULATED_NAME


def _ignore(event: RsObject) -> None:
    return None


def rs_intrinsics(rs: RsObject, i: CameraIntrinsics, model: RsObject) -> RsObject:
    """``rs.intrinsics`` of a pinhole camera (zero distortion coefficients, the given model)."""
    out = rs.intrinsics()
    out.width, out.height = i.width_px, i.height_px
    out.fx, out.fy, out.ppx, out.ppy = i.fx_px, i.fy_px, i.cx_px, i.cy_px
    out.model = model
    out.coeffs = [0.0] * 5
    return out


def rs_extrinsics(rs: RsObject, T: Mat4) -> RsObject:
    """``rs.extrinsics`` of a rigid transform (librealsense stores the rotation column-major)."""
    T = np.asarray(T, dtype=float)
    out = rs.extrinsics()
    out.rotation = [float(v) for v in T[:3, :3].flatten(order="F")]
    out.translation = [float(v) for v in T[:3, 3]]
    return out


class SoftwareD435:
    """A software device with a D435's streams; see the module docstring."""

    def __init__(self, streams: D435Streams) -> None:
        rs = pyrealsense2("a simulated RealSense recording")
        self._rs = rs
        self.streams = streams
        self.device = rs.software_device()
        self._depth_sensor = self.device.add_sensor("Stereo Module")
        self._color_sensor = self.device.add_sensor("RGB Camera")
        self._depth_profile = self._depth_sensor.add_video_stream(
            self._video_stream(rs.stream.depth, _DEPTH_UID, streams.depth, rs.format.z16, 2,
                               rs.distortion.brown_conrady), True)
        self._color_profile = self._color_sensor.add_video_stream(
            self._video_stream(rs.stream.color, _COLOR_UID, streams.color, rs.format.rgb8, 3,
                               rs.distortion.inverse_brown_conrady), True)
        self._depth_sensor.add_read_only_option(rs.option.depth_units, float(streams.depth_unit_m))
        self._depth_profile.register_extrinsics_to(self._color_profile, rs_extrinsics(rs, streams.T_color_depth))
        self.device.register_info(rs.camera_info.name, streams.name)
        self.device.register_info(rs.camera_info.serial_number, streams.serial)
        self.device.register_info(rs.camera_info.product_line, "D400")
        self._recorder: RsObject = None
        self._started = False
        self._kept: list[RsObject] = []

    def _video_stream(self, kind: RsObject, uid: int, i: CameraIntrinsics, fmt: RsObject, bpp: int,
                      model: RsObject) -> RsObject:
        vs = self._rs.video_stream()
        vs.type, vs.index, vs.uid = kind, 0, uid
        vs.width, vs.height, vs.fps, vs.bpp, vs.fmt = i.width_px, i.height_px, self.streams.fps, bpp, fmt
        vs.intrinsics = rs_intrinsics(self._rs, i, model)
        return vs

    # -- as a live device ----------------------------------------------------------------------------------------

    def add_to(self, context: RsObject) -> None:
        """Make the device one of ``context``'s devices (found by serial number; see the module docstring)."""
        kept = self._kept
        context.set_devices_changed_callback(lambda event: kept.append(event.get_new_devices()))
        self.device.add_to(context)

    def release(self, context: RsObject) -> None:
        """After the pipeline that read it stopped: the context's notification no longer reaches this device, and the
        device lists kept for it are let go."""
        context.set_devices_changed_callback(_ignore)
        self._kept.clear()

    # -- recorded --------------------------------------------------------------------------------------------------

    def record(self, path: str | Path) -> None:
        """Start pyrealsense2's recorder on this device, writing ``path`` (a ``.db3``), and start streaming."""
        self._recorder = self._rs.recorder(str(path), self.device)
        self.start()

    def start(self) -> None:
        """Open and start both sensors, their frames going nowhere but the recorder (if any)."""
        self._depth_sensor.open(self._depth_profile)
        self._color_sensor.open(self._color_profile)
        self._depth_sensor.start(lambda frame: None)
        self._color_sensor.start(lambda frame: None)
        self._started = True

    def close(self) -> None:
        """Stop streaming and finish the recording (the recorder writes the file's end when it is released)."""
        if self._started:
            for sensor in (self._depth_sensor, self._color_sensor):
                sensor.stop()
                sensor.close()
            self._started = False
        self._recorder = None

    # -- frames ---------------------------------------------------------------------------------------------------

    def z16(self, depth_m: NDArray[np.floating]) -> NDArray[np.uint16]:
        """Depth in metres (0 = invalid) as the device's Z16 picture: whole depth units, rounded."""
        steps = np.round(np.asarray(depth_m, dtype=np.float64) / self.streams.depth_unit_m)
        steps[~np.isfinite(steps)] = 0
        return np.clip(steps, 0, 65535).astype(np.uint16)

    def push(self, depth_m: NDArray[np.floating], color: NDArray[np.uint8], stamp_ns: int, number: int) -> None:
        """One frame pair: the depth imager's picture (metres) and the colour picture (RGB), both stamped
        ``stamp_ns`` (the device timestamp, ns) and numbered ``number``."""
        d, c = self.streams.depth, self.streams.color
        depth = self.z16(depth_m)
        rgb = np.ascontiguousarray(color, dtype=np.uint8)
        if depth.shape != (d.height_px, d.width_px) or rgb.shape != (c.height_px, c.width_px, 3):
            raise ValueError(f"frames of {depth.shape} and {rgb.shape} do not fit the streams "
                             f"({d.height_px}x{d.width_px} depth, {c.height_px}x{c.width_px} colour)")
        for sensor, profile, pixels, bpp in ((self._depth_sensor, self._depth_profile, depth, 2),
                                             (self._color_sensor, self._color_profile, rgb, 3)):
            frame = self._rs.software_video_frame()
            frame.pixels = pixels
            frame.stride = pixels.shape[1] * bpp
            frame.bpp = bpp
            frame.timestamp = stamp_ns / 1e6
            frame.domain = self._rs.timestamp_domain.hardware_clock
            frame.frame_number = int(number)
            frame.profile = profile.as_video_stream_profile()
            sensor.on_video_frame(frame)
