"""Recordings against the simulator they were made from (``bt-grasp camera compare``; issue 39, done-when 1).

For each scene and seed: ``camera record`` writes a recording, ``perceive REC`` (with the scene's calibration, and an
eye-in-hand recording's tool poses) and ``perceive --scene S --seed N`` perceive the same frames, and the two reports
are compared object by object: the same count and classes, centroids within :data:`CENTROID_TOLERANCE_MM`, the top
grasp within :data:`GRASP_TOLERANCE_MM` and :data:`GRASP_TOLERANCE_DEG`. The recording's depth, played back and
aligned by ``rs.align``, is compared with the simulator's own colour-aligned depth of the same moment (what a run
perceives) on the pixels valid in both: with the noise model (two independent noise draws, one in each imager) and
without it (the geometry alone: the depth imager's intrinsics and pose, and the alignment), the median of the latter
within :data:`DEPTH_TOLERANCE_MM`.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.detector.kinds import DetectorKind
from bt_grasp.geometry import rotation_angle_rad
from bt_grasp.hardware.recording_file import frames_held
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.perception.calibration_file import calibration_for_scene
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.sensing.open_source import open_source
from bt_grasp.sensing.perceive_frame import Perceiver
from bt_grasp.sensing.perceive_run import PerceiveRequest, PerceiveSummary, run_perceive
from bt_grasp.sensing.placement import FramePlacer
from bt_grasp.sensing.record_scene import record_scene
from bt_grasp.sensing.source_spec import SourceSpec

if TYPE_CHECKING:
    from bt_grasp.perception.results import Detection
    from bt_grasp.sim.simulated_d435 import D435Frame

CENTROID_TOLERANCE_MM = 1.0
GRASP_TOLERANCE_MM = 1.0
GRASP_TOLERANCE_DEG = 1.0
DEPTH_TOLERANCE_MM = 2.0


@dataclass(frozen=True)
class DepthStats:
    """Recorded-and-aligned depth minus the simulator's colour-aligned depth, on pixels valid in both."""

    median_abs_mm: float
    median_mm: float
    p95_abs_mm: float
    valid_both: float  # fraction of the picture valid in both
    valid_recorded: float  # fraction valid in the aligned recording
    valid_simulated: float

    def as_json(self) -> dict[str, float | None]:
        values = {"median_abs_mm": self.median_abs_mm, "median_mm": self.median_mm, "p95_abs_mm": self.p95_abs_mm,
                  "valid_both": self.valid_both, "valid_recorded": self.valid_recorded,
                  "valid_simulated": self.valid_simulated}
        return {k: (v if math.isfinite(v) else None) for k, v in values.items()}  # strict JSON has no infinity


#: distance bins of the measured depth noise, m
NOISE_BINS_M = ((0.3, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 1.1), (1.1, 1.3))


@dataclass(frozen=True)
class NoiseBin:
    """The noise the recording path delivers at one distance: aligned noisy minus aligned noise-free depth."""

    low_m: float
    high_m: float
    pixels: int
    rms_mm: float  # after dropping differences over 5 times the model's sigma (edge dropouts, align's fills)
    median_mm: float  # the bias rs.align's nearest-wins fill leaves on noisy depth
    model_rms_mm: float  # the noise model's sigma at the bin's middle distance

    def as_json(self) -> dict[str, float]:
        return {"low_m": self.low_m, "high_m": self.high_m, "pixels": float(self.pixels), "rms_mm": self.rms_mm,
                "median_mm": self.median_mm, "model_rms_mm": self.model_rms_mm}


def noise_bins(noisy: NDArray[np.float32], quiet: NDArray[np.float32], model_rms_m: Callable[[float], float]
               ) -> tuple[NoiseBin, ...]:
    both = (noisy > 0) & (quiet > 0)
    z, diff = quiet[both].astype(np.float64), (noisy[both].astype(np.float64) - quiet[both].astype(np.float64))
    out = []
    for low, high in NOISE_BINS_M:
        sigma = model_rms_m(0.5 * (low + high))
        sel = (z >= low) & (z < high)
        d = diff[sel]
        d = d[np.abs(d) <= 5 * sigma]
        if d.size < 100:
            continue
        out.append(NoiseBin(low, high, int(d.size), float(np.sqrt(np.mean(d ** 2)) * 1000),
                            float(np.median(d) * 1000), sigma * 1000))
    return tuple(out)


def depth_stats(recorded: NDArray[np.float32], simulated: NDArray[np.float32]) -> DepthStats:
    both = (recorded > 0) & (simulated > 0)
    diff = (recorded[both].astype(np.float64) - simulated[both].astype(np.float64)) * 1000.0
    if diff.size == 0:
        return DepthStats(math.inf, math.inf, math.inf, 0.0, float((recorded > 0).mean()),
                          float((simulated > 0).mean()))
    return DepthStats(float(np.median(np.abs(diff))), float(np.median(diff)), float(np.percentile(np.abs(diff), 95)),
                      float(both.mean()), float((recorded > 0).mean()), float((simulated > 0).mean()))


@dataclass(frozen=True)
class CaseResult:
    scene: str
    seed: int
    objects_recorded: int
    objects_simulated: int
    same_classes: bool
    centroid_mm: float  # the largest centroid difference
    grasp_mm: float  # the largest top-grasp position difference
    grasp_deg: float  # the largest top-grasp rotation difference
    depth_noisy: DepthStats
    depth_noise_free: DepthStats
    classes: tuple[str, ...]
    noise: tuple[NoiseBin, ...] = ()
    alignment: AlignmentEffect | None = None

    @property
    def passed(self) -> bool:
        return (self.objects_recorded == self.objects_simulated and self.same_classes
                and self.centroid_mm <= CENTROID_TOLERANCE_MM and self.grasp_mm <= GRASP_TOLERANCE_MM
                and self.grasp_deg <= GRASP_TOLERANCE_DEG
                and self.depth_noise_free.median_abs_mm <= DEPTH_TOLERANCE_MM)

    def as_json(self) -> dict[str, object]:
        return {"scene": self.scene, "seed": self.seed, "objects_recorded": self.objects_recorded,
                "objects_simulated": self.objects_simulated, "same_classes": self.same_classes,
                "classes": list(self.classes), "centroid_mm": self.centroid_mm, "grasp_mm": self.grasp_mm,
                "grasp_deg": self.grasp_deg, "depth_noisy": self.depth_noisy.as_json(),
                "depth_noise_free": self.depth_noise_free.as_json(), "noise": [b.as_json() for b in self.noise],
                "alignment": self.alignment.as_json() if self.alignment else None,
                "passed": self.passed}


@dataclass(frozen=True)
class CompareReport:
    cases: tuple[CaseResult, ...]

    @property
    def all_pass(self) -> bool:
        return all(c.passed for c in self.cases)

    def noise_by_distance(self) -> tuple[NoiseBin, ...]:
        """Every case's noise bins pooled (RMS weighted by pixels; the median is the pixel-weighted mean of the
        cases' medians)."""
        pooled = []
        for low, high in NOISE_BINS_M:
            bins = [b for c in self.cases for b in c.noise if (b.low_m, b.high_m) == (low, high)]
            n = sum(b.pixels for b in bins)
            if n:
                rms = math.sqrt(sum(b.pixels * b.rms_mm ** 2 for b in bins) / n)
                median = sum(b.pixels * b.median_mm for b in bins) / n
                pooled.append(NoiseBin(low, high, n, rms, median, bins[0].model_rms_mm))
        return tuple(pooled)

    def as_json(self) -> dict[str, object]:
        return {"cases": [c.as_json() for c in self.cases], "all_pass": self.all_pass,
                "noise_by_distance": [b.as_json() for b in self.noise_by_distance()],
                "tolerances": {"centroid_mm": CENTROID_TOLERANCE_MM, "grasp_mm": GRASP_TOLERANCE_MM,
                               "grasp_deg": GRASP_TOLERANCE_DEG, "depth_median_mm": DEPTH_TOLERANCE_MM}}

    def lines(self) -> list[str]:
        out = [f"{'scene':12} {'seed':>4} {'objects':>8} {'classes':>8} {'centroid':>9} {'grasp':>14} "
               f"{'depth noise-free':>17} {'depth noisy':>18} result",
               f"{'':12} {'':>4} {'rec/sim':>8} {'':>8} {'max mm':>9} {'max mm / deg':>14} "
               f"{'median |d| mm':>17} {'median |d|, d mm':>18}"]
        for c in self.cases:
            out.append(f"{c.scene:12} {c.seed:>4} {c.objects_recorded:>3}/{c.objects_simulated:<4} "
                       f"{'same' if c.same_classes else 'DIFFER':>8} {c.centroid_mm:9.4f} "
                       f"{c.grasp_mm:7.4f}/{c.grasp_deg:6.4f} {c.depth_noise_free.median_abs_mm:17.3f} "
                       f"{c.depth_noisy.median_abs_mm:9.3f},{c.depth_noisy.median_mm:8.3f} "
                       f"{'pass' if c.passed else 'FAIL'}")
        effects = [c.alignment for c in self.cases if c.alignment is not None and c.alignment.matched]
        if effects:
            out.append("what the depth imager's offset and rs.align do to perception, noise-free (recording minus the "
                       "simulator's own aligned depth), all cases: "
                       f"centroids {np.median([e.centroid_median_mm for e in effects]):.2f} mm median, "
                       f"{max(e.centroid_max_mm for e in effects):.2f} mm at most; footprints "
                       f"{np.median([e.footprint_median_mm for e in effects]):+.2f} mm, heights "
                       f"{np.median([e.height_median_mm for e in effects]):+.2f} mm (medians of the cases' medians); "
                       f"{sum(e.objects_recorded for e in effects)} objects seen in the recordings, "
                       f"{sum(e.objects_simulated for e in effects)} in the simulator's depth")
        pooled = self.noise_by_distance()
        if pooled:
            out.append("depth noise through the recording path (aligned noisy minus aligned noise-free), all cases:")
            out.extend(f"  {b.low_m:.1f}-{b.high_m:.1f} m: RMS {b.rms_mm:.2f} mm (model {b.model_rms_mm:.2f} mm), "
                       f"median {b.median_mm:+.2f} mm, {b.pixels} pixels" for b in pooled)
        out.append(f"{sum(c.passed for c in self.cases)} of {len(self.cases)} cases pass (centroids <= "
                   f"{CENTROID_TOLERANCE_MM} mm, top grasp <= {GRASP_TOLERANCE_MM} mm and {GRASP_TOLERANCE_DEG} deg, "
                   f"noise-free aligned depth median <= {DEPTH_TOLERANCE_MM} mm)")
        return out


def _objects_compared(a: PerceiveSummary, b: PerceiveSummary) -> tuple[int, int, bool, float, float, float,
                                                                      tuple[str, ...]]:
    count_a = sum(len(f.objects) for f in a.reports)
    count_b = sum(len(f.objects) for f in b.reports)
    same = len(a.reports) == len(b.reports)
    centroid = grasp_mm = grasp_deg = 0.0
    classes: list[str] = []
    for fa, fb in zip(a.reports, b.reports, strict=False):
        if len(fa.objects) != len(fb.objects):
            same = False
            continue
        for oa, ob in zip(fa.objects, fb.objects, strict=True):
            classes.append(oa.name)
            if (oa.class_name, oa.label, oa.shape_class) != (ob.class_name, ob.label, ob.shape_class):
                same = False
            centroid = max(centroid, 1000 * float(np.linalg.norm(np.subtract(oa.centroid_m, ob.centroid_m))))
            if bool(oa.grasps) != bool(ob.grasps):
                same = False
            elif oa.grasps:
                ga, gb = oa.grasps[0].T_frame_tcp, ob.grasps[0].T_frame_tcp
                grasp_mm = max(grasp_mm, 1000 * float(np.linalg.norm(ga[:3, 3] - gb[:3, 3])))
                grasp_deg = max(grasp_deg, math.degrees(rotation_angle_rad(ga[:3, :3], gb[:3, :3])))
    return count_a, count_b, same, centroid, grasp_mm, grasp_deg, tuple(classes)


def _recorded_depth(path: Path, count: int) -> list[NDArray[np.float32]]:
    # deferred: pyrealsense2 only when a RealSense source is asked for
    from bt_grasp.hardware.realsense_open import open_recording

    out = []
    with open_recording(path) as camera:
        for _ in range(count):
            frame = camera.capture()
            if frame is None:
                break
            out.append(frame.depth_m)
    return out


def _depth(scene_path: Path, config: Scene, seed: int, frames: int, out: Path
           ) -> tuple[DepthStats, NDArray[np.float32], list[D435Frame]]:
    """Record ``config`` (its noise model as it is), play the recording back, compare its aligned depth with the
    simulator's colour-aligned depth of the same frames (all frames' pixels together); also the aligned depth and
    the simulator's frames."""
    simulated: list[D435Frame] = []
    record_scene(scene_path, seed, out, frames, config=config, on_frame=simulated.append)
    played = _recorded_depth(out, frames)
    if len(played) != len(simulated):
        held = ", ".join(f"{count} on {name}" for name, count in sorted(frames_held(out).items()))
        raise RuntimeError(f"{out}: {len(played)} of the {len(simulated)} frames recorded came back (the file holds "
                           f"{held or 'no picture'})")
    recorded = np.concatenate([r.ravel() for r in played])
    own = np.concatenate([s.aligned_depth_m.ravel() for s in simulated])
    return depth_stats(recorded, own), recorded, simulated


@dataclass(frozen=True)
class AlignmentEffect:
    """What the depth imager's offset and ``rs.align`` do to perception, without noise: the objects perceived in
    the recording against those perceived in the simulator's own colour-aligned depth of the same frames (matched
    by nearest centroid, within 3 cm)."""

    objects_recorded: int
    objects_simulated: int
    matched: int
    centroid_max_mm: float
    centroid_median_mm: float
    footprint_median_mm: float  # recorded minus simulated length and width, median (align's fill widens objects)
    height_median_mm: float

    def as_json(self) -> dict[str, float | None]:
        values = {"objects_recorded": float(self.objects_recorded), "objects_simulated": float(self.objects_simulated),
                  "matched": float(self.matched), "centroid_max_mm": self.centroid_max_mm,
                  "centroid_median_mm": self.centroid_median_mm, "footprint_median_mm": self.footprint_median_mm,
                  "height_median_mm": self.height_median_mm}
        return {k: (v if math.isfinite(v) else None) for k, v in values.items()}


def _alignment_effect(scene_path: Path, config: Scene, recording: Path, simulated: list[D435Frame],
                      calibration: Path | None, detector: DetectorKind) -> AlignmentEffect:
    # deferred: open3d (~1 s) only when a frame is perceived
    from bt_grasp.perception.config import PerceptionConfig

    # deferred: the simulator only when a scene is asked for
    from bt_grasp.sensing.scene_camera import tool_pose

    from_file = run_perceive(PerceiveRequest(SourceSpec.recording(recording), calibration, detector, len(simulated)))
    recorded = [o for f in from_file.reports for o in f.objects]
    opened = open_source(SourceSpec.recording(recording), calibration)  # the placer, the source's intrinsics
    opened.close()
    intrinsics = opened.camera.intrinsics
    poses = {raw.stamp_ns: tool_pose(config, raw.q_rad, raw.stamp_ns) for raw in simulated}
    placer = opened.placer
    if placer.calibration is not None and Mount(placer.calibration.mount) is Mount.EYE_IN_HAND:
        placer = FramePlacer(placer.calibration, placer.calibration_path, poses.get, "simulated arm")
    perceiver = Perceiver(PerceptionConfig.for_scene(config), config, detector)
    own: list[Detection] = []
    for raw in simulated:
        frame = RGBDFrame(raw.color, raw.aligned_depth_m, intrinsics, raw.stamp_ns, opened.camera.mount)
        seen = perceiver.perceive(frame, placer.place(frame, perceiver.config))
        own.extend(seen.result.others)
    pairs = []
    for obj in recorded:
        best = min(own, key=lambda d: float(np.linalg.norm(np.subtract(d.centroid_base_m, obj.centroid_m))),
                   default=None)
        if best is not None and np.linalg.norm(np.subtract(best.centroid_base_m, obj.centroid_m)) < 0.03:
            pairs.append((obj, best))
    if not pairs:
        return AlignmentEffect(len(recorded), len(own), 0, math.nan, math.nan, math.nan, math.nan)
    offsets = [1000 * float(np.linalg.norm(np.subtract(d.centroid_base_m, o.centroid_m))) for o, d in pairs]
    footprint = [1000 * (o.size_m[i] - d.size_m[i]) for o, d in pairs for i in (0, 1)]
    height = [1000 * (o.size_m[2] - d.size_m[2]) for o, d in pairs]
    return AlignmentEffect(len(recorded), len(own), len(pairs), max(offsets), float(np.median(offsets)),
                           float(np.median(footprint)), float(np.median(height)))


def compare_case(scene_path: Path, seed: int, frames: int, detector: DetectorKind, folder: Path) -> CaseResult:
    config = load_scene(scene_path)
    calibration, _ = calibration_for_scene(config, scene_path, None)
    name = scene_path.stem
    recording = folder / f"{name}_{seed}.db3"
    noisy, noisy_depth, _ = _depth(scene_path, config, seed, frames, recording)
    quiet = config.model_copy(update={"camera": config.camera.model_copy(
        update={"noise": config.camera.noise.model_copy(update={"enabled": False})})})
    quiet_recording = folder / f"{name}_{seed}_noise_free.db3"
    noise_free, quiet_depth, quiet_frames = _depth(scene_path, quiet, seed, frames, quiet_recording)
    alignment = _alignment_effect(scene_path, quiet, quiet_recording, quiet_frames, calibration,
                                  detector)
    # deferred: the simulator (sapien) only when a scene is asked for
    from bt_grasp.sim.noise import depth_rms_m

    model = config.camera.noise
    bins = noise_bins(noisy_depth, quiet_depth, lambda z: float(depth_rms_m(z, model)))
    # the same run seed on both sides: the same perception, grasp and IK streams (``bt_grasp.seeds``)
    from_file = run_perceive(PerceiveRequest(SourceSpec.recording(recording), calibration, detector, frames,
                                             seed=seed))
    from_scene = run_perceive(PerceiveRequest(SourceSpec.simulated(scene_path, seed), None, detector, frames,
                                              seed=seed))
    count_a, count_b, same, centroid, grasp_mm, grasp_deg, classes = _objects_compared(from_file, from_scene)
    return CaseResult(name, seed, count_a, count_b, same, centroid, grasp_mm, grasp_deg, noisy, noise_free, classes,
                      bins, alignment)


def compare_cases(scenes: Iterable[Path], seeds: Iterable[int], frames: int, detector: DetectorKind,
                  folder: Path | None = None) -> CompareReport:
    seeds = list(seeds)
    with tempfile.TemporaryDirectory(prefix="bt-grasp-compare-") as tmp:
        where = Path(folder) if folder is not None else Path(tmp)
        where.mkdir(parents=True, exist_ok=True)
        cases = tuple(compare_case(Path(scene), seed, frames, detector, where) for scene in scenes for seed in seeds)
    return CompareReport(cases)
