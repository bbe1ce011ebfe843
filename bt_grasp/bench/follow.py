"""Benchmarks of visual following on the conveyor, judged against the simulator's truth (bench only).

* ``run_tracking_bench``: ``trees/follow_conveyor.xml`` (FollowTarget at a 15 cm standoff, never ending) on
  the conveyor scenes of both mounts at several belt speeds; the tracking error of a tick is the horizontal
  distance between the followed object's true centre and the tool's (tcp's) z axis, taken while
  FollowTarget runs, from 3 s after it started (the approach from the home or view pose is excluded) to the
  end of the episode (8 s of simulated time).
* ``run_conveyor_pick_bench``: ``trees/pick_from_conveyor.xml``, success judged by physics (held and lifted).
* ``run_sort_bench``: ``trees/sort_from_conveyor.xml`` on ``scenes/conveyor_sort.yaml`` (the scene's collect goal:
  N objects placed in the bin, judged by physics); picks per minute = N / the episode's simulated time x 60 (from
  the start: the 3 s before the first object enters and the judge's settling count).
* ``issue_table``: issue 45's rows (eye-to-hand at 10, 20, 30 and 50 cm/s; eye-in-hand at 20 cm/s; household
  objects at 30 cm/s; picks per minute into a bin at 30 cm/s), with the perception latency the scenes declare
  (the package default, 0.100 s: every row states it).

The belt speed is the only change to the shipped scene files (a copy with ``speed_m_s`` set is written to a
temporary folder; its calibration path and its meshes' paths are made absolute).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import yaml

from bt_grasp.episode.episode import Episode
from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.episode.result import EpisodeResult
from bt_grasp.tree.loader import LoadedTree

SCENES = {"eye-to-hand": "scenes/conveyor.yaml", "eye-in-hand": "scenes/conveyor_eye_in_hand.yaml"}
#: FollowTarget's scenes: the object on the belt from the start (the pick scenes feed theirs in from upstream)
FOLLOW_SCENES = {"eye-to-hand": "scenes/conveyor_follow.yaml", "eye-in-hand": "scenes/conveyor_follow_eye_in_hand.yaml"}
HOUSEHOLD_SCENE = "scenes/conveyor_household.yaml"
SORT_SCENE = "scenes/conveyor_sort.yaml"
FOLLOW_TREE = "trees/follow_conveyor.xml"
PICK_TREE = "trees/pick_from_conveyor.xml"
SORT_TREE = "trees/sort_from_conveyor.xml"
#: issue 45's rows: (what, scene file, belt speed m/s, tree)
ISSUE_ROWS: tuple[tuple[str, str, float, str], ...] = (
    *((f"eye-to-hand {round(v * 100)} cm/s", SCENES["eye-to-hand"], v, PICK_TREE) for v in (0.10, 0.20, 0.30, 0.50)),
    ("eye-in-hand 20 cm/s", SCENES["eye-in-hand"], 0.20, PICK_TREE),
    ("household 30 cm/s", HOUSEHOLD_SCENE, 0.30, PICK_TREE),
    ("into a bin 30 cm/s", SORT_SCENE, 0.30, SORT_TREE),
)
_SETTLE_S = 3.0
_FOLLOW_TICKS = 800


def scene_at_speed(repo: Path, mount: str, speed_m_s: float, folder: Path) -> Path:
    """A copy of the mount's following scene with the belt at ``speed_m_s``."""
    return scene_file_at_speed(repo / FOLLOW_SCENES[mount], speed_m_s, folder)


def scene_file_at_speed(source: Path, speed_m_s: float, folder: Path) -> Path:
    """A copy of a conveyor scene file with the belt at ``speed_m_s`` (paths it names made absolute)."""
    data = yaml.safe_load(source.read_text())
    for fixture in data.get("fixtures", []):
        if fixture.get("kind") == "conveyor":
            fixture["speed_m_s"] = float(speed_m_s)
            for obj in (fixture.get("feed") or {}).get("objects", []):
                if "mesh" in obj:
                    obj["mesh"] = str((source.parent / obj["mesh"]).resolve())
    data["calibration"] = str((source.parent / data["calibration"]).resolve())
    path = folder / f"{source.stem}_{round(speed_m_s * 1000)}mm_s.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _pct(values: Sequence[float], q: float) -> float:
    return float(np.percentile(values, q)) if len(values) else float("nan")


def _figure(value: float) -> float | None:
    """A figure for JSON: None (null) where there was nothing to measure (NaN is not JSON, RFC 8259)."""
    return None if value != value else value


def _follow_errors(episode: Episode, target: str) -> tuple[list[float], Callable[[int, LoadedTree], None]]:
    from bt_grasp.sim.oracle import GroundTruthOracle

    oracle = GroundTruthOracle(episode.world)
    errors: list[float] = []
    started: list[float] = []

    def on_tick(tick: int, tree: LoadedTree) -> None:
        running = [n for n in tree.nodes() if n.bt_type == "FollowTarget" and n.status.name == "RUNNING"]
        if not running:
            return
        now = episode.world.now_ns() * 1e-9
        if not started:
            started.append(now)
        if now - started[0] < _SETTLE_S:
            return
        T_tcp = oracle.T_world_tcp()
        p = oracle.T_world_object(target)[:3, 3] - T_tcp[:3, 3]
        axis = T_tcp[:3, 2]
        errors.append(float(np.linalg.norm(p - (p @ axis) * axis)))

    return errors, on_tick


def run_tracking_bench(repo: Path, speeds_m_s: Sequence[float], seeds: int, mounts: Sequence[str] = tuple(SCENES),
                       color: str = "red", target: str = "red_box",
                       progress: Callable[[str], None] | None = None) -> dict[str, object]:
    t0 = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for mount in mounts:
            for speed in speeds_m_s:
                scene = scene_at_speed(repo, mount, speed, Path(tmp))
                errors: list[float] = []
                lost = 0
                for seed in range(seeds):
                    request = EpisodeRequest(tree=repo / FOLLOW_TREE, scene=scene, seed=seed,
                                             max_ticks=_FOLLOW_TICKS, blackboard={"color": color})
                    episode = Episode(request)
                    sample, on_tick = _follow_errors(episode, target)
                    result = episode.run([on_tick])
                    lost += int(result.reason == "TARGET_LOST")
                    errors.extend(sample)
                    if progress is not None:
                        progress(f"{mount} {speed * 100:.0f} cm/s seed {seed}: {len(sample)} samples, "
                                 f"median {_pct(sample, 50) * 1e3:.1f} mm, {result.reason or 'running'}")
                mm = [e * 1e3 for e in errors]
                rows.append({"mount": mount, "speed_cm_s": round(speed * 100, 1), "episodes": seeds,
                             "samples": len(mm), "median_mm": _figure(_pct(mm, 50)), "p95_mm": _figure(_pct(mm, 95)),
                             "max_mm": max(mm) if mm else None, "target_lost": lost})
    return {"rows": rows, "elapsed_s": time.perf_counter() - t0}


def run_conveyor_pick_bench(repo: Path, speed_m_s: float, seeds: int, mount: str = "eye-to-hand",
                            color: str = "red", first_seed: int = 0,
                            progress: Callable[[str], None] | None = None,
                            scene_file: str | None = None) -> dict[str, object]:
    t0 = time.perf_counter()
    ok = 0
    reasons: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        scene = scene_file_at_speed(repo / (scene_file or SCENES[mount]), speed_m_s, Path(tmp))
        latency = _latency(scene)
        for seed in range(first_seed, first_seed + seeds):
            request = EpisodeRequest(tree=repo / PICK_TREE, scene=scene, seed=seed,
                                     blackboard={"color": color, "lift_height": 0.15})
            result = Episode(request).run()
            ok += int(result.success)
            if not result.success:
                key = _failure(result)
                reasons[key] = reasons.get(key, 0) + 1
            if progress is not None:
                where = f" ({Path(scene_file).stem})" if scene_file else ""
                progress(f"{mount}{where} {speed_m_s * 100:.0f} cm/s seed {seed}: {result.success} "
                         f"{'' if result.success else _failure(result)}")
    return {"mount": mount, "speed_cm_s": round(speed_m_s * 100, 1), "episodes": seeds, "successes": ok,
            "success_rate": ok / max(seeds, 1), "failures": reasons, "first_seed": first_seed,
            "perception_latency_s": latency, "elapsed_s": time.perf_counter() - t0}


def _failure(result: EpisodeResult) -> str:
    """A failure's key: the failed leaf's reason, or the judge's unmet condition when the tree succeeded."""
    if result.reason is None:  # the tree succeeded; the judge did not (e.g. the object rose 12 of 15 cm)
        return f"GOAL_NOT_MET ({result.judged.failed_condition})"
    return f"{result.reason}@{result.failed_leaf}"


def _latency(scene: Path) -> float:
    from bt_grasp.scene.format import load_scene

    return load_scene(scene).latency_s


def run_sort_bench(repo: Path, speed_m_s: float, seeds: int, first_seed: int = 0,
                   progress: Callable[[str], None] | None = None) -> dict[str, object]:
    """``trees/sort_from_conveyor.xml``: success (the collect goal met by physics) and picks per minute."""
    from bt_grasp.scene.format import load_scene
    from bt_grasp.scene.goals import CollectGoal

    t0 = time.perf_counter()
    ok = 0
    reasons: dict[str, int] = {}
    rates: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        scene = scene_file_at_speed(repo / SORT_SCENE, speed_m_s, Path(tmp))
        goal, latency = load_scene(scene).goal, _latency(scene)
        assert isinstance(goal, CollectGoal)
        for seed in range(first_seed, first_seed + seeds):
            result = Episode(EpisodeRequest(tree=repo / SORT_TREE, scene=scene, seed=seed)).run()
            ok += int(result.success)
            if result.success:
                rates.append(goal.count / result.sim_time_s * 60.0)
            else:
                key = _failure(result)
                reasons[key] = reasons.get(key, 0) + 1
            if progress is not None:
                progress(f"into a bin {speed_m_s * 100:.0f} cm/s seed {seed}: {result.success} "
                         f"{'' if result.success else _failure(result)} {result.sim_time_s:.1f} s")
    return {"mount": "eye-to-hand", "speed_cm_s": round(speed_m_s * 100, 1), "episodes": seeds, "successes": ok,
            "success_rate": ok / max(seeds, 1), "failures": reasons, "first_seed": first_seed,
            "objects_per_episode": goal.count, "picks_per_min_median": _figure(_pct(rates, 50)),
            "picks_per_min_min": min(rates) if rates else None,
            "picks_per_min_max": max(rates) if rates else None,
            "perception_latency_s": latency, "elapsed_s": time.perf_counter() - t0}


def issue_table(repo: Path, seeds: int, first_seed: int = 0, only: Sequence[str] = (),
                progress: Callable[[str], None] | None = None) -> list[dict[str, object]]:
    """Issue 45's rows (:data:`ISSUE_ROWS`; ``only``: the rows whose names contain one of these words)."""
    rows = []
    for what, scene, speed, tree in ISSUE_ROWS:
        if only and not any(word in what for word in only):
            continue
        if tree == SORT_TREE:
            row = run_sort_bench(repo, speed, seeds, first_seed, progress)
        else:
            mount = "eye-in-hand" if scene == SCENES["eye-in-hand"] else "eye-to-hand"
            row = run_conveyor_pick_bench(repo, speed, seeds, mount, color="", first_seed=first_seed,
                                          progress=progress, scene_file=scene)  # any object, as the goal says
        rows.append({"row": what, "scene": scene, **row})
    return rows
