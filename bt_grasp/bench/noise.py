"""The sensor-noise sweep: detection rate and centroid/yaw error at 1x-4x the default stereo error.

Each seeded random scene (as ``bench.random_scene`` draws it) is rendered once without noise; the backend
then applies the scene's noise model at every level of :data:`NOISE_LEVELS` with its own seeded generator,
so all levels see exactly the same scenes and differ only in the sensor. Perception runs with the camera
pose from one hand-eye calibration made at the default noise (as a deployed cell would have it), with the
settings it ships with (noise adaptation on) unless ``adapt=False`` asks for the fixed thresholds.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from bt_grasp.bench.perception import DETECTED_WITHIN_M, random_scene, yaw_error_deg
from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.pipeline import perceive
from bt_grasp.scene.format import DepthNoise, Scene

#: the issue's table: (subpixel, edge_dropout, color_sigma) per level; 1x is the scene default
NOISE_LEVELS: dict[str, tuple[float, float, float]] = {
    "1x": (0.08, 0.5, 2.0),
    "2x": (0.16, 0.7, 4.0),
    "3x": (0.25, 0.9, 6.0),
    "4x": (0.32, 0.95, 8.0),
}


@dataclass
class _Tally:
    """One noise level's counts and samples over the scenes."""

    detected: int = 0
    centroid_mm: list[float] = field(default_factory=list)
    yaw_deg: list[float] = field(default_factory=list)
    ms: list[float] = field(default_factory=list)
    statuses: dict[str, int] = field(default_factory=dict)
    sigma_mm: list[float] = field(default_factory=list)


class SweepBackend(Protocol):
    def base_scene(self) -> Scene: ...

    def capture_levels(self, scene: Scene, seed: int, noises: Sequence[DepthNoise]
                       ) -> tuple[list[RGBDFrame | None], dict[str, Mat4]]:
        """One frame per noise model of the same settled scene, and every object's true ``T_base_object``."""
        ...

    def calibrate(self, scene: Scene, mount: str, seed: int, poses: int) -> tuple[Mat4, dict[str, tuple[float, float]]]:
        ...


def level_noise(base: DepthNoise, level: str) -> DepthNoise:
    subpixel, dropout, color_sigma = NOISE_LEVELS[level]
    return base.model_copy(update={"enabled": True, "subpixel": subpixel, "edge_dropout": dropout,
                                   "color_sigma": color_sigma})


def _pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


def run_noise_sweep(scenes: int, seed: int, *, backend: SweepBackend, adapt: bool = True,
                    calibration_poses: int = 16, levels: Sequence[str] = tuple(NOISE_LEVELS),
                    progress: Callable[[int, int], None] | None = None) -> dict[str, object]:
    """Run the sweep; returns a JSON-able summary with one row per level."""
    t0 = time.perf_counter()
    base = backend.base_scene()
    T_base_camera, _ = backend.calibrate(base, Mount.EYE_TO_HAND, seed, calibration_poses)
    config = PerceptionConfig.for_scene(base)
    config = config.model_copy(update={"noise": config.noise.model_copy(update={"adapt": adapt})})
    noises = [level_noise(base.camera.noise, lv) for lv in levels]
    rng = np.random.default_rng(seed)
    rows = {lv: _Tally() for lv in levels}
    for i in range(scenes):
        scene = random_scene(base, rng, i)
        frames, truth = backend.capture_levels(scene, seed + 1000 + i, noises)
        target = scene.objects[0]
        for lv, frame in zip(levels, frames, strict=True):
            row = rows[lv]
            result = perceive(frame, T_base_camera, config, str(target.color))
            row.statuses[result.status.value] = row.statuses.get(result.status.value, 0) + 1
            row.ms.append(result.timings_ms.get("total", float("nan")))
            if result.noise is not None:
                row.sigma_mm.append(result.noise.sigma_m * 1e3)
            det = result.best
            if det is None:
                continue
            err = float(np.linalg.norm(det.centroid - truth[target.name][:3, 3]))
            if err < DETECTED_WITHIN_M:
                row.detected += 1
                row.centroid_mm.append(err * 1e3)
                yaw = yaw_error_deg(det.yaw_rad, truth[target.name], target.dims_m)
                if yaw is not None:
                    row.yaw_deg.append(yaw)
        if progress is not None:
            progress(i + 1, scenes)
    out: dict[str, dict[str, object]] = {}
    for lv in levels:
        row = rows[lv]
        subpixel, dropout, color_sigma = NOISE_LEVELS[lv]
        out[lv] = {
            "subpixel": subpixel, "edge_dropout": dropout, "color_sigma": color_sigma,
            "detection_rate": row.detected / max(scenes, 1),
            "centroid_err_mm_median": _pct(row.centroid_mm, 50), "centroid_err_mm_p95": _pct(row.centroid_mm, 95),
            "yaw_err_deg_median": _pct(row.yaw_deg, 50), "yaw_err_deg_p95": _pct(row.yaw_deg, 95),
            "measured_sigma_mm_median": _pct(row.sigma_mm, 50),
            "perception_ms_median": _pct(row.ms[1:] or row.ms, 50),
            "statuses": row.statuses,
        }
    return {"scenes": scenes, "seed": seed, "adapt": adapt, "levels": out, "elapsed_s": time.perf_counter() - t0}
