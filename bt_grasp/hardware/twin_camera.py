"""A twin's camera read as a live RealSense D435: the twin's frames fed into a pyrealsense2 ``software_device`` in this
process and read back through :class:`~bt_grasp.hardware.realsense_camera.RealSenseCamera`, the class that reads a real
D435 (its pipeline, the frame pairing, the filters, ``rs.align``).

The transport is the twin's camera port (``bt_grasp.sim.twin.camera_port`` documents the protocol): once ``streams``
(both imagers' intrinsics, the depth-to-colour extrinsics, the depth unit: what a D435's stream profiles carry), then
``frame`` per capture (the colour picture and the depth imager's Z16 picture of the cell as it is when asked).
Everything read is bounded and checked before use: a header line of at most :data:`MAX_HEADER_BYTES`, a JSON object
of exactly the expected keys and types, a payload of exactly the size the streams imply, every read within
``timeout_s``. Anything else is one sentence (:class:`TwinCameraError`); a frame the twin could not render, or one
that did not come in time, is a dropped frame (``capture`` returns None), as a live camera's is.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import socket
from typing import Any

import numpy as np

from bt_grasp.errors import BtGraspError
from bt_grasp.hardware.realsense_camera import RealSenseCamera
from bt_grasp.hardware.realsense_lib import pyrealsense2
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.hardware.software_d435 import D435Streams, SoftwareD435
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame

log = logging.getLogger(__name__)

MAX_HEADER_BYTES = 4096
MAX_SIDE_PX = 4096
#: a frame request may take this long (the twin renders two pictures, ~40-90 ms, longer on a busy machine)
FRAME_TIMEOUT_S = 10.0


class TwinCameraError(BtGraspError):
    """The twin's camera port cannot be used, or sent something that is not its protocol: one sentence."""

    exit_code = 2


def _intrinsics(value: object, what: str) -> CameraIntrinsics:
    keys = ("width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px")
    if not isinstance(value, dict) or set(value) != set(keys):
        raise TwinCameraError(f"the twin's camera described its {what} stream without {', '.join(keys)}")
    w, h = value["width_px"], value["height_px"]
    if not (isinstance(w, int) and isinstance(h, int) and 0 < w <= MAX_SIDE_PX and 0 < h <= MAX_SIDE_PX):
        raise TwinCameraError(f"the twin's camera gave its {what} stream a size of {w!r} x {h!r} pixels")
    numbers = [value[k] for k in keys[2:]]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in numbers):
        raise TwinCameraError(f"the twin's camera gave its {what} stream intrinsics that are not finite numbers")
    fx, fy, cx, cy = (float(v) for v in numbers)
    if fx <= 0 or fy <= 0:
        raise TwinCameraError(f"the twin's camera gave its {what} stream a focal length that is not positive")
    return CameraIntrinsics(w, h, fx, fy, cx, cy)


def parse_streams(reply: dict[str, Any]) -> tuple[D435Streams, Mount]:
    """The ``streams`` reply as the software device's streams; TwinCameraError (one sentence) when malformed."""
    keys = {"ok", "color", "depth", "T_color_depth", "depth_unit_m", "fps", "serial", "mount"}
    if set(reply) != keys:
        raise TwinCameraError(f"the twin's camera described its streams with the keys {sorted(reply)}, not "
                              f"{sorted(keys)}")
    color, depth = _intrinsics(reply["color"], "colour"), _intrinsics(reply["depth"], "depth")
    T = reply["T_color_depth"]
    if not (isinstance(T, list) and len(T) == 4 and all(isinstance(r, list) and len(r) == 4 for r in T)
            and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for r in T for v in r)):
        raise TwinCameraError("the twin's camera gave depth-to-colour extrinsics that are not a finite 4x4 matrix")
    T_color_depth = np.array(T, dtype=float)
    R = T_color_depth[:3, :3]
    if not (np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.allclose(T_color_depth[3], [0, 0, 0, 1])):
        raise TwinCameraError("the twin's camera gave depth-to-colour extrinsics that are not a rigid transform")
    unit, fps, serial, mount = reply["depth_unit_m"], reply["fps"], reply["serial"], reply["mount"]
    if not (isinstance(unit, float) and 1e-5 <= unit <= 0.01):
        raise TwinCameraError(f"the twin's camera gave a depth unit of {unit!r} m (expected 1e-5 to 0.01)")
    if not (isinstance(fps, int) and 1 <= fps <= 300):
        raise TwinCameraError(f"the twin's camera gave a frame rate of {fps!r}")
    if not (isinstance(serial, str) and serial.isalnum() and len(serial) <= 32):
        raise TwinCameraError("the twin's camera gave a serial number that is not 1-32 letters and digits")
    if mount not in (m.value for m in Mount):
        raise TwinCameraError(f"the twin's camera gave a mount of {str(mount)[:40]!r}")
    return D435Streams(color=color, depth=depth, T_color_depth=T_color_depth, fps=fps, depth_unit_m=unit,
                       serial=serial, name="Intel RealSense D435 (bt_grasp twin)"), Mount(mount)


class TwinCameraLink:
    """The socket to the twin's camera port (one request at a time)."""

    def __init__(self, host: str, port: int, timeout_s: float = FRAME_TIMEOUT_S) -> None:
        self.host, self.port, self.timeout_s = host, port, timeout_s
        try:
            self._sock = socket.create_connection((host, port), timeout=min(timeout_s, 5.0))
        except OSError as exc:
            raise TwinCameraError(f"the twin's camera at {host}:{port} cannot be reached ({exc.strerror or exc}): is "
                                  "`bt-grasp twin` running there?") from None
        self._buffer = b""

    def close(self) -> None:
        self._sock.close()

    def request(self, line: str) -> dict[str, Any]:
        self._sock.settimeout(self.timeout_s)
        self._sock.sendall(line.encode("ascii") + b"\n")
        return self._header()

    def _header(self) -> dict[str, Any]:
        while (end := self._buffer.find(b"\n")) < 0:
            if len(self._buffer) > MAX_HEADER_BYTES:
                raise TwinCameraError(f"the twin's camera sent {len(self._buffer)} bytes without a line end (a reply "
                                      f"header is at most {MAX_HEADER_BYTES})")
            self._recv(MAX_HEADER_BYTES)
        raw, self._buffer = self._buffer[:end], self._buffer[end + 1:]
        if len(raw) > MAX_HEADER_BYTES:
            raise TwinCameraError(f"the twin's camera sent a reply header of {len(raw)} bytes (at most "
                                  f"{MAX_HEADER_BYTES})")
        try:
            value = json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
        except (UnicodeDecodeError, ValueError):
            raise TwinCameraError("the twin's camera sent a reply header that is not a JSON object") from None
        if not isinstance(value, dict) or not isinstance(value.get("ok"), bool):
            raise TwinCameraError("the twin's camera sent a reply header that is not a JSON object with ok")
        return value

    def payload(self, size: int) -> bytes:
        while len(self._buffer) < size:
            self._recv(min(1 << 20, size - len(self._buffer)))
        out, self._buffer = self._buffer[:size], self._buffer[size:]
        return out

    def _recv(self, most: int) -> None:
        try:
            chunk = self._sock.recv(most)
        except TimeoutError:
            raise TimeoutError(f"the twin's camera sent nothing for {self.timeout_s:g} s") from None
        if not chunk:
            raise ConnectionError("the twin's camera port closed the connection")
        self._buffer += chunk


def _no_constant(name: str) -> float:
    raise ValueError(name)


class TwinD435Camera:
    """Implements :class:`bt_grasp.interfaces.Camera`: the twin's camera through pyrealsense2 (module docstring)."""

    def __init__(self, host: str, port: int, settings: RealSenseSettings = RealSenseSettings()) -> None:
        # deferred: pyrealsense2's device opening only when a camera is opened
        from bt_grasp.hardware.realsense_open import open_device

        rs = pyrealsense2("the twin's camera (it is read through pyrealsense2, as a real D435)")
        self.link = TwinCameraLink(host, port)
        try:
            reply = self.link.request("streams")
            if not reply["ok"]:
                raise TwinCameraError(f"the twin's camera refused to describe its streams: {_error(reply)}")
            self.streams, mount = parse_streams(reply)
        except (OSError, TimeoutError) as exc:
            self.link.close()
            raise TwinCameraError(f"the twin's camera at {host}:{port} failed: {exc}") from None
        except TwinCameraError:
            self.link.close()
            raise
        self.device = SoftwareD435(self.streams)
        self._context = rs.context()
        self.device.add_to(self._context)
        c = self.streams.color
        # each frame is pushed before it is waited for, so the timeout only guards against a stuck library
        live = dataclasses.replace(settings, width_px=c.width_px, height_px=c.height_px, fps=self.streams.fps,
                                   settle_frames=0)
        self.camera: RealSenseCamera = open_device(self.streams.serial, live, mount, self._context)
        self._expected = c.width_px * c.height_px * 3 + self.streams.depth.width_px * self.streams.depth.height_px * 2
        self._number = 0
        self.dropped = 0

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.camera.intrinsics

    @property
    def mount(self) -> Mount:
        return self.camera.mount

    def capture(self) -> RGBDFrame | None:
        """The cell as it is now, through pyrealsense2; None when the twin rendered nothing in time."""
        try:
            reply = self.link.request("frame")
        except (OSError, TimeoutError) as exc:
            log.warning("the twin's camera: %s (a dropped frame)", exc)
            self.dropped += 1
            return None
        if not reply["ok"]:
            log.warning("the twin's camera: %s (a dropped frame)", _error(reply))
            self.dropped += 1
            return None
        if set(reply) != {"ok", "stamp_ns", "number", "bytes"}:
            raise TwinCameraError(f"the twin's camera sent a frame header with the keys {sorted(reply)}")
        stamp, size = reply["stamp_ns"], reply["bytes"]
        if not (isinstance(stamp, int) and stamp >= 0 and isinstance(size, int)):
            raise TwinCameraError("the twin's camera sent a frame header whose stamp or size is not an integer")
        if size != self._expected:
            raise TwinCameraError(f"the twin's camera announced a frame of {size} bytes; its streams make "
                                  f"{self._expected}")
        try:
            data = self.link.payload(size)
        except (OSError, TimeoutError) as exc:
            raise TwinCameraError(f"the twin's camera stopped in the middle of a frame: {exc}") from None
        c, d = self.streams.color, self.streams.depth
        split = c.width_px * c.height_px * 3
        color = np.frombuffer(data[:split], dtype=np.uint8).reshape(c.height_px, c.width_px, 3)
        z16 = np.frombuffer(data[split:], dtype="<u2").reshape(d.height_px, d.width_px)
        self._number += 1
        self.device.push(z16.astype(np.float64) * self.streams.depth_unit_m, color, stamp, self._number)
        return self.camera.capture()

    def close(self) -> None:
        """Stop the pipeline, then let go of the software device and the socket (``SceneD435Camera``'s order)."""
        self.camera.close()
        self.device.release(self._context)
        self.link.close()


def _error(reply: dict[str, Any]) -> str:
    error = reply.get("error")
    return error[:200] if isinstance(error, str) else "no reason given"
