"""Frames fed into pyrealsense2 itself (no stand-in for it): software D435s, a thread feeding one like a live
camera, recordings written with the library's recorder. Synthetic pictures, so no simulator is needed here."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.hardware.software_d435 import D435Streams, SoftwareD435
from bt_grasp.interfaces import CameraIntrinsics

W, H = 64, 48
PERIOD_NS = 33_333_333


def streams(serial: str = "000000000001", *, same_imager: bool = False) -> D435Streams:
    """Small D435-like streams; ``same_imager``: depth with the colour imager's intrinsics and pose (align is then
    the identity, so aligned depth equals what was written)."""
    color = CameraIntrinsics(W, H, 60.0, 60.0, (W - 1) / 2, (H - 1) / 2)
    depth = color if same_imager else CameraIntrinsics(W, H, 38.0, 38.0, (W - 1) / 2, (H - 1) / 2)
    T = np.eye(4)
    if not same_imager:
        T[:3, 3] = (0.015, 0.0, 0.0)
    return D435Streams(color=color, depth=depth, T_color_depth=T, fps=30, serial=serial)


def picture(k: int, seed: int = 0) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
    """Frame ``k``: a plane 0.7 m away plus k mm, with a seeded speckle, and a colour picture whose red channel is
    ``k``."""
    rng = np.random.default_rng([seed, k])
    depth = (0.700 + 0.001 * k + rng.normal(0.0, 0.002, (H, W))).astype(np.float32)
    color = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    color[..., 0] = k % 256
    return depth, color


def write_recording(path: Path, frames: int, *, same_imager: bool = True) -> list[tuple[Any, Any]]:
    """Record ``frames`` frames with pyrealsense2's recorder; returns the pictures written."""
    device = SoftwareD435(streams(same_imager=same_imager))
    device.record(path)
    written = []
    for k in range(frames):
        depth, color = picture(k)
        device.push(depth, color, 1_000_000_000 + k * PERIOD_NS, k)
        written.append((depth, color))
    device.close()
    del device
    return written


class Feeder:
    """Pushes frames into a software device from a thread at 30 fps, as a live camera's USB stream arrives."""

    def __init__(self, device: SoftwareD435) -> None:
        self.device = device
        self.pushed = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            depth, color = picture(self.pushed)
            self.device.push(depth, color, self.pushed * PERIOD_NS, self.pushed)
            self.pushed += 1
            time.sleep(PERIOD_NS / 1e9)

    def __enter__(self) -> Feeder:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)

    def __exit__(self, *exc: object) -> None:
        self.stop()
