"""Perception accuracy benchmark: seeded random tabletop scenes, scored against the simulator's truth.

This module holds the scene randomisation, the loop and the scoring; it never imports the simulator. The
simulator side (building a world per scene, capturing, reading true poses, calibrating) is a
:class:`BenchBackend` the composition root passes in (``bt_grasp.bench.sim_backend.SimBenchBackend``).

Per scene: one target object (random colour, shape, size, pose) and 1-3 distractors of other colours,
camera noise on; perception runs with the camera pose from one hand-eye calibration made at the start
(eye-to-hand, as the pick uses it), so the errors are end to end. Yaw errors are taken modulo the
footprint's symmetry (90 degrees for a square footprint, 180 otherwise; none for cylinders).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Literal, Protocol

import numpy as np

from bt_grasp.geometry import Mat4
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.perception.grasps import synthesize_grasps
from bt_grasp.perception.pipeline import perceive
from bt_grasp.scene.format import Scene
from bt_grasp.scene.objects import ObjectPose, Randomize, SceneObject

log = logging.getLogger(__name__)

BENCH_COLORS = ("red", "green", "blue", "yellow", "orange", "purple")
DETECTED_WITHIN_M = 0.02  # a detection further than this from the true centroid counts as a miss


class BenchBackend(Protocol):
    def base_scene(self) -> Scene: ...

    def capture(self, scene: Scene, seed: int) -> tuple[RGBDFrame | None, dict[str, Mat4]]:
        """One noisy frame of the settled scene and the true ``T_base_object`` of every object."""
        ...

    def calibrate(self, scene: Scene, mount: str, seed: int, poses: int) -> tuple[Mat4, dict[str, tuple[float, float]]]:
        """(estimated X, {method: (true error mm, deg)}) of one simulated hand-eye calibration."""
        ...


def random_scene(base: Scene, rng: np.random.Generator, index: int) -> Scene:
    """A tabletop scene with one target (objects[0]) and 1-3 distractors of other colours."""
    colors = list(rng.permutation(BENCH_COLORS))
    n = 1 + int(rng.integers(1, 4))
    ws = base.workspace
    cx, cy = float(np.mean(ws.x_m)), float(np.mean(ws.y_m))
    x_range = (ws.x_m[0] - cx + 0.06, ws.x_m[1] - cx - 0.06)
    y_range = (ws.y_m[0] - cy + 0.06, ws.y_m[1] - cy - 0.06)
    objects = []
    for k in range(n):
        if rng.random() < 0.75:
            size: tuple[float, ...] = (float(rng.uniform(0.03, 0.065)), float(rng.uniform(0.03, 0.07)),
                                       float(rng.uniform(0.03, 0.08)))
            shape: Literal["box", "cylinder"] = "box"
        else:
            size = (float(rng.uniform(0.018, 0.03)), float(rng.uniform(0.04, 0.09)))
            shape = "cylinder"
        objects.append(SceneObject(
            name=f"obj{k}", shape=shape, size_m=size, color=str(colors[k]),
            pose=ObjectPose(xy_m=(cx, cy)),
            randomize=Randomize(x_m=x_range, y_m=y_range, yaw_deg=(-90.0, 90.0)),
        ))
    return base.model_copy(update={"objects": tuple(objects), "name": f"bench_{index}"})


def yaw_error_deg(measured_rad: float, T_base_object: Mat4, size_m: tuple[float, ...]) -> float | None:
    """Yaw error modulo the footprint symmetry; None for a round footprint."""
    if len(size_m) != 3:
        return None
    yaw = float(np.degrees(np.arctan2(T_base_object[1, 0], T_base_object[0, 0])))
    if size_m[1] > size_m[0]:
        yaw += 90.0
    period = 90.0 if abs(size_m[0] - size_m[1]) < 0.004 else 180.0
    d = (float(np.degrees(measured_rad)) - yaw) % period
    return min(d, period - d)


def _stats(values: list[float]) -> dict[str, float]:
    if not values:
        return {"median": float("nan"), "p95": float("nan"), "max": float("nan")}
    a = np.asarray(values, dtype=float)
    return {"median": float(np.median(a)), "p95": float(np.percentile(a, 95)), "max": float(a.max())}


def run_perception_bench(scenes: int, seed: int, *, backend: BenchBackend, calibrate: bool = True,
                         calibration_poses: int = 16,
                         progress: Callable[[int, int], None] | None = None) -> dict[str, object]:
    """Run the benchmark; returns a JSON-able summary (see docs/perception.md for the fields)."""
    t_start = time.perf_counter()
    base = backend.base_scene()
    calib_report: dict[str, dict[str, dict[str, float]]] = {}
    if calibrate:
        for mount in Mount:
            for noise in (True, False):
                scene = base.model_copy(update={"camera": base.camera.model_copy(
                    update={"noise": base.camera.noise.model_copy(update={"enabled": noise})})})
                _, errors = backend.calibrate(scene, mount, seed, calibration_poses)
                calib_report[f"{mount}/{'noise' if noise else 'no_noise'}"] = {
                    k: {"true_error_mm": round(v[0], 4), "true_error_deg": round(v[1], 5)} for k, v in errors.items()
                }
    T_base_camera, _ = backend.calibrate(base, Mount.EYE_TO_HAND, seed, calibration_poses)
    config = PerceptionConfig.for_scene(base)
    rng = np.random.default_rng(seed)
    centroid_mm: list[float] = []
    yaw_deg: list[float] = []
    totals: list[float] = []
    stages: dict[str, list[float]] = {}
    detected = 0
    grasp_ok = 0
    statuses: dict[str, int] = {}
    for i in range(scenes):
        scene = random_scene(base, rng, i)
        frame, truth = backend.capture(scene, seed + 1000 + i)
        target = scene.objects[0]
        result = perceive(frame, T_base_camera, config, str(target.color))
        statuses[result.status.value] = statuses.get(result.status.value, 0) + 1
        if i > 0:  # the first call pays open3d's one-off start-up
            totals.append(result.timings_ms.get("total", float("nan")))
            for name, ms in result.timings_ms.items():
                stages.setdefault(name, []).append(ms)
        det = result.best
        if det is not None:
            err = float(np.linalg.norm(det.centroid - truth[target.name][:3, 3]))
            if err < DETECTED_WITHIN_M:
                detected += 1
                centroid_mm.append(err * 1e3)
                y = yaw_error_deg(det.yaw_rad, truth[target.name], target.dims_m)
                if y is not None:
                    yaw_deg.append(y)
                grasp_ok += int(synthesize_grasps(det, result.others).ok)
        if progress is not None:
            progress(i + 1, scenes)
    summary: dict[str, object] = {
        "scenes": scenes,
        "seed": seed,
        "detection_rate": detected / max(scenes, 1),
        "grasp_rate": grasp_ok / max(scenes, 1),
        "statuses": statuses,
        "centroid_err_mm_median": _stats(centroid_mm)["median"],
        "centroid_err_mm": _stats(centroid_mm),
        "yaw_err_deg_median": _stats(yaw_deg)["median"],
        "yaw_err_deg": _stats(yaw_deg),
        "perception_ms_median": _stats(totals)["median"],
        "perception_ms": _stats(totals),
        "stage_ms_median": {k: float(np.median(v)) for k, v in stages.items()},
        "calibration": calib_report,
        "elapsed_s": time.perf_counter() - t_start,
    }
    return summary
