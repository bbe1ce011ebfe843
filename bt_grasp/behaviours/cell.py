"""What robot leaves receive in ``setup(cell=...)``: the robot, the camera and the pipeline's services."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from bt_grasp.clock import Clock
from bt_grasp.interfaces import Camera, RGBDFrame, Robot
from bt_grasp.scene_config import Scene


class MediaSink(Protocol):
    """Where leaves send what they saw and computed (the run's MCAP recorder, or nothing)."""

    def frame(self, frame: RGBDFrame, T_base_camera: NDArray[np.float64] | None) -> None: ...

    def perception(self, result: Any, T_base_camera: NDArray[np.float64]) -> None: ...

    def grasps(self, candidates: Sequence[Any]) -> None: ...

    def trajectory(self, name: str, times_s: NDArray[np.float64], q: NDArray[np.float64], kind: str) -> None: ...

    def log(self, level: str, name: str, message: str) -> None: ...


class NullSink:
    def frame(self, frame: RGBDFrame, T_base_camera: NDArray[np.float64] | None) -> None:
        return None

    def perception(self, result: Any, T_base_camera: NDArray[np.float64]) -> None:
        return None

    def grasps(self, candidates: Sequence[Any]) -> None:
        return None

    def trajectory(self, name: str, times_s: NDArray[np.float64], q: NDArray[np.float64], kind: str) -> None:
        return None

    def log(self, level: str, name: str, message: str) -> None:
        return None


@dataclass
class Cell:
    """The hardware and services the leaves share during one run.

    ``calibration`` is filled by ``LoadCalibration``/``Calibrate`` (or ``--calibration``); leaves that need
    the camera pose fail with CALIBRATION_MISSING until then. ``services`` holds replaceable pipeline
    pieces (planner, perception config, ...), which fault injectors may wrap.
    """

    robot: Robot
    camera: Camera
    clock: Clock
    scene: Scene
    seed: int
    services: dict[str, Any] = field(default_factory=dict)
    calibration: Any = None
    media: MediaSink = field(default_factory=NullSink)
    workdir: Path = Path(".")
    extras: Mapping[str, Any] = field(default_factory=dict)

    def service(self, name: str) -> Any:
        return self.services[name]
