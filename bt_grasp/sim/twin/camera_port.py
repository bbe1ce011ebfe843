"""The twin's camera port (not a UR port; 30101 by default): a run's frames, as a D435 delivers them.

A run against the twin reads its camera through the RealSense camera class a real cell uses
(``bt_grasp.hardware.twin_camera``): it feeds what this port sends into a pyrealsense2 ``software_device`` in its
own process and reads it back through the library's pipeline and ``rs.align``. The port sends what a D435's USB
stream carries, the colour picture and the depth imager's own Z16 picture, plus (once) what its stream profiles
carry: both imagers' intrinsics, the depth-to-colour extrinsics, the depth unit.

The protocol, one request line in, one reply out, on one connection as long as the client likes:

    streams\\n   ->  one JSON line: {"ok": true, "color": {intrinsics}, "depth": {intrinsics},
                                    "T_color_depth": [[4x4]], "depth_unit_m": 0.001, "fps": 30,
                                    "serial": "...", "mount": "eye-to-hand"}
    frame\\n     ->  one JSON line: {"ok": true, "stamp_ns": N, "number": K, "bytes": B}, then B bytes: the
                    colour picture (RGB8, row-major, height x width x 3) and the depth picture (Z16
                    little-endian, height x width) of the streams' sizes; the frame shows the cell as it is
                    when the request arrives (rendered in the camera's process, ~40-90 ms)

Anything else is answered ``{"ok": false, "error": "<one sentence>"}``. Requests are at most
:data:`MAX_REQUEST_BYTES` and must be finished within the twin's message timeout; each connection is served by a
thread of its own with socket timeouts, at most :data:`MAX_CONNECTIONS` at a time. Nothing read is evaluated.
"""

from __future__ import annotations

import contextlib
import json
import logging
import socket
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_grasp.interfaces import CameraIntrinsics
from bt_grasp.sim.twin.camera_worker import D435Pair
from bt_grasp.sim.twin.netio import listening_socket

log = logging.getLogger(__name__)

MAX_REQUEST_BYTES = 64
MAX_CONNECTIONS = 4
#: a reply that cannot be sent within this (the client stopped reading) closes the connection
SEND_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class D435Description:
    """What a D435's stream profiles say, as the twin serves it."""

    color: CameraIntrinsics
    depth: CameraIntrinsics
    T_color_depth: np.ndarray
    mount: str
    depth_unit_m: float = 0.001
    fps: int = 30
    serial: str = "000000000436"

    def to_json(self) -> dict[str, Any]:
        return {"color": self.color.to_dict(), "depth": self.depth.to_dict(),
                "T_color_depth": [[float(v) for v in row] for row in self.T_color_depth],
                "depth_unit_m": self.depth_unit_m, "fps": self.fps, "serial": self.serial, "mount": self.mount}


def z16(depth_m: np.ndarray, unit_m: float) -> np.ndarray:
    """Metres (0 = invalid) as whole depth units, little-endian (as ``SoftwareD435.z16`` rounds)."""
    steps = np.round(np.asarray(depth_m, dtype=np.float64) / unit_m)
    steps[~np.isfinite(steps)] = 0
    return np.clip(steps, 0, 65535).astype("<u2")


class CameraPort:
    """Serves :data:`D435Description` and frames from ``capture`` on ``(host, port)``."""

    def __init__(self, host: str, port: int, description: D435Description, capture: Callable[[], D435Pair],
                 message_timeout_s: float = 5.0) -> None:
        self.host, self.port = host, port
        self.description = description
        self._capture = capture
        self._timeout_s = message_timeout_s
        self._sock: socket.socket | None = None
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._conns: set[socket.socket] = set()
        self._lock = threading.Lock()
        self._number = 0

    def bind(self) -> None:
        sock = listening_socket(self.host, self.port, "camera", backlog=4)
        sock.settimeout(0.2)
        self._sock = sock

    def start(self) -> None:
        thread = threading.Thread(target=self._accept_loop, name="twin-camera-port", daemon=True)
        thread.start()
        self._threads.append(thread)

    def stop(self) -> None:
        self._stop.set()
        with self._lock:
            conns = list(self._conns)
        for conn in conns:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        for thread in self._threads:
            thread.join(timeout=2.0)
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def _accept_loop(self) -> None:
        assert self._sock is not None
        while not self._stop.is_set():
            try:
                conn, addr = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            peer = f"{addr[0]}:{addr[1]}"
            with self._lock:
                if len(self._conns) >= MAX_CONNECTIONS:
                    log.warning("camera connection from %s refused: %d connections are open already (the twin's "
                                "limit)", peer, MAX_CONNECTIONS)
                    conn.close()
                    continue
                self._conns.add(conn)
            log.info("camera connection from %s", peer)
            thread = threading.Thread(target=self._serve, args=(conn, peer), name="twin-camera-client", daemon=True)
            thread.start()
            self._threads = [t for t in self._threads if t.is_alive()] + [thread]

    def _serve(self, conn: socket.socket, peer: str) -> None:
        buffer = b""
        try:
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            while not self._stop.is_set():
                conn.settimeout(None if not buffer else self._timeout_s)  # idle waits; a begun request must finish
                try:
                    chunk = conn.recv(MAX_REQUEST_BYTES + 1)
                except TimeoutError:
                    log.warning("camera connection from %s closed: a request begun was not finished within %g s",
                                peer, self._timeout_s)
                    return
                if not chunk:
                    return
                buffer += chunk
                while (end := buffer.find(b"\n")) >= 0:
                    line, buffer = buffer[:end].strip(), buffer[end + 1:]
                    conn.settimeout(SEND_TIMEOUT_S)
                    self._answer(conn, line)
                if len(buffer) > MAX_REQUEST_BYTES:
                    log.warning("camera connection from %s closed: %d bytes without a line end (a request is at "
                                "most %d)", peer, len(buffer), MAX_REQUEST_BYTES)
                    return
        except OSError as exc:
            log.info("camera connection from %s closed: %s", peer, exc.strerror or exc)
        finally:
            with self._lock:
                self._conns.discard(conn)
            with contextlib.suppress(OSError):
                conn.close()

    def _answer(self, conn: socket.socket, line: bytes) -> None:
        if line == b"streams":
            conn.sendall(_line({"ok": True, **self.description.to_json()}))
            return
        if line != b"frame":
            shown = line[:40].decode("ascii", "replace")
            log.warning("camera request refused: %r is not streams or frame", shown)
            conn.sendall(_line({"ok": False, "error": f"unknown request {shown!r}; expected streams or frame"}))
            return
        try:
            pair = self._capture()
        except (TimeoutError, OSError, EOFError, RuntimeError) as exc:
            conn.sendall(_line({"ok": False, "error": f"the twin's camera rendered nothing: {exc}"}))
            return
        unit = self.description.depth_unit_m
        payload = np.ascontiguousarray(pair.color, dtype=np.uint8).tobytes() + z16(pair.depth_m, unit).tobytes()
        self._number += 1
        conn.sendall(_line({"ok": True, "stamp_ns": int(pair.stamp_ns), "number": self._number,
                            "bytes": len(payload)}) + payload)


def _line(obj: dict[str, Any]) -> bytes:
    return (json.dumps(obj) + "\n").encode()
