"""Where one warm pick's time goes (`bt-grasp bench budget`), by stage, with the floor beside it.

One episode runs as a warm-up (imports, the renderer's start-up, first pictures); the next, the measured one,
runs with timers around the seams each stage passes through, installed for that episode only:

| stage | measured around |
| --- | --- |
| physics | ``World.step`` (PhysX steps and the arm's controller before each) |
| rendering | ``SimCamera.capture/render_true/render_color_async`` and ``PendingPicture.result`` |
| perception | ``bt_grasp.perception.pipeline.perceive`` |
| planning | ``MotionPlanner.plan_to_pose/plan_to_joints/straight_line/checker`` |
| leaves' own work | every leaf's ``initialise/update/terminate`` (trajectories, IK, grasp logic, executor) |
| tree (py_trees) | ``LoadedTree.tick``: py_trees' traversal, ports, the blackboard |
| status bookkeeping | the runner's ``tick_records`` and the recorder's node differ |
| blackboard differ | ``LoadedTree.blackboard_values`` and the recorder's blackboard differ |
| recording | every ``RunRecorder`` write and the log's extra frames (``LogExtras``) |
| judge | ``Judge.observe`` after every tick (the benchmark's oracle, not the pipeline) |

Time is exclusive: a stage inside another (a picture inside Perceive's update) counts once, for the inner one.
What no timer covers is "everything else". The floor is the physics of the same number of steps measured
alone (`bench sim`'s swinging arm, in the same process) plus one warm capture. Wall time is reported only;
no decision of the run reads it, and the timers change no result (the same tick stream with and without).
"""

from __future__ import annotations

import functools
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, ParamSpec, TypedDict, TypeVar

from bt_grasp.process.environment import machine_description

if TYPE_CHECKING:
    from bt_grasp.tree.loader import LoadedTree

_P = ParamSpec("_P")
_R = TypeVar("_R")

#: the stages in the order they are printed, with the issue's group each belongs to
STAGES: tuple[tuple[str, str], ...] = (
    ("physics", "physics"),
    ("rendering", "rendering"),
    ("perception", "perception"),
    ("planning", "planning"),
    ("tree (py_trees)", "tree and blackboard"),
    ("status bookkeeping", "tree and blackboard"),
    ("blackboard differ", "tree and blackboard"),
    ("recording", "recording"),
    ("leaves' own work", "everything else"),
    ("judge", "everything else"),
)


@dataclass
class StageClock:
    """Exclusive time per stage, from wrapped callables (one thread). ``now``: the clock read, wall time by
    default; ``time.thread_time`` counts the tick loop thread's CPU time instead, which a loaded machine
    disturbs far less (``tools/warm_pick_cpu.py``)."""

    now: Callable[[], float] = time.perf_counter
    totals: dict[str, float] = field(default_factory=lambda: {name: 0.0 for name, _ in STAGES})
    calls: dict[str, int] = field(default_factory=lambda: {name: 0 for name, _ in STAGES})
    _stack: list[list[float]] = field(default_factory=list)  # [start, time spent in inner stages]

    def wrap(self, stage: str, fn: Callable[_P, _R]) -> Callable[_P, _R]:
        stack, totals, calls, now = self._stack, self.totals, self.calls, self.now

        @functools.wraps(fn)
        def timed(*args: _P.args, **kwargs: _P.kwargs) -> _R:
            stack.append([now(), 0.0])
            try:
                return fn(*args, **kwargs)
            finally:
                start, inner = stack.pop()
                spent = now() - start
                totals[stage] += spent - inner
                calls[stage] += 1
                if stack:
                    stack[-1][1] += spent

        return timed


@contextmanager
def timed_seams(clock: StageClock) -> Iterator[Callable[[LoadedTree], None]]:
    """Install the timers on the classes and functions named in the module's table; removed on exit.
    Yields a function that also times one tree's leaves (their instances' lifecycle methods)."""
    from bt_grasp.episode.observers import LogExtras
    from bt_grasp.motion.planner import MotionPlanner
    from bt_grasp.perception import pipeline
    from bt_grasp.recording import jsonable
    from bt_grasp.recording.writer import RunRecorder
    from bt_grasp.sim import camera
    from bt_grasp.sim.judge import Judge
    from bt_grasp.sim.world import World
    from bt_grasp.tree import loader, runner

    seams: list[tuple[object, str, str]] = [
        (World, "step", "physics"),
        (camera.SimCamera, "capture", "rendering"),
        (camera.SimCamera, "render_true", "rendering"),
        (camera.SimCamera, "render_color_async", "rendering"),
        (camera.PendingPicture, "result", "rendering"),
        (pipeline, "perceive", "perception"),
        *((MotionPlanner, name, "planning") for name in ("plan_to_pose", "plan_to_joints", "straight_line",
                                                          "checker")),
        (loader.LoadedTree, "tick", "tree (py_trees)"),
        (runner, "tick_records", "status bookkeeping"),
        (jsonable.NodeDiffer, "diff", "status bookkeeping"),
        (loader.LoadedTree, "blackboard_values", "blackboard differ"),
        (jsonable.BlackboardDiffer, "diff", "blackboard differ"),
        *((RunRecorder, name, "recording") for name in vars(RunRecorder)
          if not name.startswith("_") and callable(vars(RunRecorder)[name])),
        (LogExtras, "__call__", "recording"),
        (LogExtras, "finish", "recording"),
        (Judge, "observe", "judge"),
    ]
    saved = [(owner, name, vars(owner)[name]) for owner, name, _ in seams]
    instances: list[tuple[object, str]] = []

    def time_leaves(tree: LoadedTree) -> None:
        for node in tree.nodes():
            if type(node).__module__.startswith("bt_grasp.behaviours"):
                for name in ("initialise", "update", "terminate"):
                    setattr(node, name, clock.wrap("leaves' own work", getattr(node, name)))
                    instances.append((node, name))

    try:
        for owner, name, stage in seams:
            setattr(owner, name, clock.wrap(stage, vars(owner)[name]))
        yield time_leaves
    finally:
        for owner, name, original in saved:
            setattr(owner, name, original)
        for node, name in instances:
            delattr(node, name)


class StageTime(TypedDict):
    stage: str
    group: str
    s: float
    calls: int
    share: float


class BudgetReport(TypedDict):
    """``run_budget_bench``'s figures."""

    machine: str
    tree: str
    scene: str
    seed: int
    log: bool
    success: bool
    ticks: int
    same_as_warmup: bool
    sim_time_s: float
    physics_steps: int
    episode_wall_s: float
    tick_loop_wall_s: float
    stages: list[StageTime]
    tick_loop_overhead_us_per_tick: dict[str, float]
    floor: dict[str, float]
    wall_over_floor: float


def _floor(scene: Path, physics_steps: int, dt_s: float) -> dict[str, float]:
    """The physics of ``physics_steps`` steps alone and one warm capture, measured here and now."""
    from bt_grasp.bench.sim import run_sim_bench

    sim = run_sim_bench(scene, captures=5, physics_seconds=max(1.0, physics_steps * dt_s))
    physics_s = physics_steps / float(sim["physics_steps_per_s"])
    capture_s = float(sim["capture_ms_median"]) / 1e3
    return {"physics_s": physics_s, "capture_s": capture_s, "floor_s": physics_s + capture_s,
            "physics_steps_per_s": float(sim["physics_steps_per_s"])}


def run_budget_bench(tree: Path, scene: Path, seed: int, calibration: Path | None, log: bool,
                     now: Callable[[], float] = time.perf_counter) -> BudgetReport:
    """One warm-up pick, then the measured one (same seed) with the stage timers; the floor beside it (wall
    time). ``now``: the stages' and the episode's clock (``time.thread_time``: the tick loop thread's CPU)."""

    with tempfile.TemporaryDirectory(prefix="bt_grasp_budget_") as work:  # the measured run's log, removed after
        return _budget(tree, scene, seed, calibration, Path(work) / "run.mcap" if log else None, now)


def _budget(tree: Path, scene: Path, seed: int, calibration: Path | None, log: Path | None,
            now: Callable[[], float]) -> BudgetReport:
    from bt_grasp.episode import Episode, WarmWorlds, pick_request

    worlds = WarmWorlds()
    warmup = Episode(pick_request(tree, scene, seed, calibration=calibration), worlds).run()  # not measured
    request = pick_request(tree, scene, seed, calibration=calibration, log=log)
    clock = StageClock(now)
    episode = Episode(request, worlds)
    steps_before = episode.world.physics_steps
    with timed_seams(clock) as time_leaves:
        time_leaves(episode.tree)
        start = now()
        result = episode.run()
        total_s = now() - start
    steps = episode.world.physics_steps - steps_before
    floor = _floor(scene, steps, episode.world.dt_s)
    stages: list[StageTime] = [
        {"stage": name, "group": group, "s": round(clock.totals[name], 4), "calls": clock.calls[name],
         "share": round(clock.totals[name] / total_s, 3)} for name, group in STAGES]
    other_s = total_s - sum(clock.totals.values())
    stages.append({"stage": "everything else", "group": "everything else", "s": round(other_s, 4), "calls": 0,
                   "share": round(other_s / total_s, 3)})
    ticks = result.ticks
    per_tick_us = {name: round(clock.totals[name] / ticks * 1e6, 1)
                   for name in ("tree (py_trees)", "status bookkeeping", "blackboard differ", "recording")}
    return {
        "machine": machine_description(),
        "tree": str(tree), "scene": str(scene), "seed": seed, "log": log is not None,
        "success": result.success, "ticks": ticks,
        # the timers change nothing the run decides: the warm-up's outcome, tick count and final object poses
        "same_as_warmup": (result.success, result.ticks, result.judged)
        == (warmup.success, warmup.ticks, warmup.judged),
        "sim_time_s": round(result.sim_time_s, 3),
        "physics_steps": steps,
        "episode_wall_s": round(total_s, 4),  # Episode.run(): tick loop, settling, judge, log open/close
        "tick_loop_wall_s": round(result.wall_time_s, 4),  # what `bench pick` reports as wall time
        "stages": stages,
        "tick_loop_overhead_us_per_tick": {**per_tick_us,
                                           "total": round(sum(per_tick_us.values()), 1)},
        "floor": {k: round(v, 4) for k, v in floor.items()},
        "wall_over_floor": round(total_s / floor["floor_s"], 2),
    }
