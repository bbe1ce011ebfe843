"""Seeded picks judged by physics, per tree (`bt-grasp bench pick`): success, times, plan calls, planning time,
and per object picked (a scene of many kinds of object: which object each run lifted, and why each failure
failed).

Which object a run picks is the tree's choice, never the simulator's: the ``color`` entry (``red`` by default,
today's figures); on a scene that declares mesh or URDF objects, no colour at all, so ``Perceive`` takes the most
graspable object it sees, by geometry. The judge (ground truth, benchmark side) then names the object that rose
most as the one picked.

With ``detector="learned"`` (issue 23: picking by class) each seed names its target: one of the objects that seed
puts on the table (:func:`class_target`, drawn from the scene file and the seed on the benchmark side, as the
world draws them), whose class goes to the tree's ``class`` entry and whose colour to its ``color`` entry; the
judge checks that very object (``PickGoal.object``). A tree that picks by class (``trees/pick_class.xml``) and one
that picks by colour (``trees/pick_with_recovery.xml``, the geometric detector) thus chase the same objects on the
same seeds.
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
from collections import Counter
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, NotRequired, TypedDict

from bt_grasp.errors import LayoutError
from bt_grasp.interfaces import Mount
from bt_grasp.process.environment import machine_description

if TYPE_CHECKING:
    from bt_grasp.episode import EpisodeResult


class ObjectFigures(TypedDict):
    """The runs of one tree that lifted one object (the judge names it)."""

    runs: int
    successes: int
    failures: dict[int, str]  # seed -> why
    failure_reasons: dict[str, int]


class TreeFigures(TypedDict):
    """One tree's picks over the seeds."""

    runs: int
    successes: int
    success_rate: float
    failures: dict[int, str]  # seed -> reason (failed leaf)
    per_object: dict[str, ObjectFigures]
    sim_time_s_median: float
    wall_time_s_median: float
    ticks_median: float
    retries_total: int
    plan_calls_per_pick_mean: float
    plan_pose_calls_per_pick_mean: float
    plan_wall_s_per_pick_median: float
    plan_wall_s_per_pick_mean: float


class PickBench(TypedDict):
    """``run_pick_bench``'s figures."""

    machine: str
    scene: str
    calibration: str
    color: str
    trees: dict[str, TreeFigures]
    detector: NotRequired[str]
    targets: NotRequired[dict[int, str]]
    worlds: NotRequired[str]
    #: seeds whose objects the scene cannot lay out without overlapping (bt_grasp.errors.LayoutError): not run
    unplaced_seeds: NotRequired[dict[int, str]]


def default_pick_trees(detector: str = "geometric") -> list[Path]:
    """The trees `bench pick` runs when none is named: today's pick and its recovery by colour; with the learned
    detector, the pick by class and, on the same targets by colour, the geometric recovery tree beside it."""
    first = Path("trees/pick_class.xml") if detector == "learned" else Path("trees/pick.xml")
    return [first, Path("trees/pick_with_recovery.xml")]


def run_pick_bench(
    trees: list[Path], scene: Path, seeds: int, first_seed: int, calibration: Path | None, log_dir: Path | None,
    warm: bool = False, color: str | None = None, progress: Callable[[str], None] | None = None,
    detector: str = "geometric",
) -> PickBench:
    """``color``: the colour the tree picks ('' = any object: the most graspable one Perceive sees); None: red,
    or any object when the scene declares a mesh or URDF object (:func:`default_color`). ``detector``:
    "learned" names a target per seed (see the module's text; ``color`` is then ignored)."""
    from bt_grasp.episode import (
        FreshWorlds,
        WarmWorlds,
        WorldSource,
        pick_request,
        run_episode,
    )
    from bt_grasp.episode.calibration import calibrate_in_sim
    from bt_grasp.perception.calibration_file import save_calibration
    from bt_grasp.scene.format import load_scene
    from bt_grasp.scene.goals import PickGoal
    from bt_grasp.scene.run_goal import default_color

    if color is None:
        color = default_color(load_scene(scene).objects)

    work = Path(tempfile.mkdtemp(prefix="bt_grasp_bench_"))  # its calibration; removed at the end
    try:
        if calibration is None:
            calibration = save_calibration(
                calibrate_in_sim(scene, Mount.EYE_TO_HAND, first_seed).run.calibration, work / "calibration.yaml"
            )
        report: PickBench = {
            "machine": machine_description(), "scene": str(scene), "calibration": str(calibration),
            "color": color or "any (the most graspable object Perceive sees)", "trees": {}
        }
        targets = ({seed: class_target(scene, seed) for seed in range(first_seed, first_seed + seeds)}
                   if detector == "learned" else None)
        if targets is not None:
            report["detector"] = "learned"
            report["color"] = "per seed: the target's colour"
            report["targets"] = {seed: f"{t[0]} (class {t[1]}, {t[2]})" for seed, t in targets.items()}
        worlds: WorldSource = WarmWorlds() if warm else FreshWorlds()
        report["worlds"] = ("warm (a renderer kept warm; each episode's world built afresh)" if warm
                            else "fresh (a new world per episode)")
        unplaced: dict[int, str] = {}
        for tree in trees:
            runs: list[EpisodeResult] = []
            for seed in range(first_seed, first_seed + seeds):
                log = (log_dir / f"{tree.stem}_seed{seed}.mcap") if log_dir is not None else None
                request = pick_request(tree, scene, seed, calibration=calibration, log=log)
                if targets is not None:
                    name, class_name, target_color = targets[seed]
                    request = replace(request, goal=PickGoal(kind="pick", object=name), blackboard={
                        **request.blackboard, "class": class_name, "color": target_color, "detector": detector})
                elif color != "red":
                    request = replace(request, goal=PickGoal(kind="pick", color=color or None),
                                      blackboard={**request.blackboard, "color": color})
                try:
                    runs.append(run_episode(request, worlds=worlds))
                except LayoutError as exc:  # this seed's draw, not the file: listed, and the others still run
                    unplaced[seed] = exc.problem
                    if progress is not None:
                        progress(f"{tree.name} seed {seed}: not run: {exc.problem}")
                    continue
                if progress is not None:
                    progress(f"{tree.name} seed {seed}: {_outcome(runs[-1])}")
            if not runs:
                first = min(unplaced)
                raise LayoutError(scene, f"none of seeds {first_seed}..{first_seed + seeds - 1} lays the objects out "
                                  f"without overlapping (seed {first}: {unplaced[first]})")
            if unplaced:
                report["unplaced_seeds"] = dict(sorted(unplaced.items()))
            ok = [r for r in runs if r.success]
            report["trees"][str(tree)] = {
                "runs": len(runs),
                "successes": len(ok),
                "success_rate": len(ok) / len(runs),
                "failures": {r.seed: f"{r.reason} ({r.failed_leaf})" for r in runs if not r.success},
                "per_object": _per_object(runs),
                "sim_time_s_median": round(statistics.median(r.sim_time_s for r in runs), 3),
                "wall_time_s_median": round(statistics.median(r.wall_time_s for r in runs), 3),
                "ticks_median": statistics.median(r.ticks for r in runs),
                "retries_total": sum(sum(r.retries.values()) for r in runs),
                "plan_calls_per_pick_mean": round(statistics.mean(r.planning.calls for r in runs), 2),
                "plan_pose_calls_per_pick_mean": round(statistics.mean(r.planning.pose_calls for r in runs), 2),
                "plan_wall_s_per_pick_median": round(statistics.median(r.planning.wall_s for r in runs), 4),
                "plan_wall_s_per_pick_mean": round(statistics.mean(r.planning.wall_s for r in runs), 4),
            }
        return report
    finally:
        shutil.rmtree(work, ignore_errors=True)  # it was left behind in the temporary folder


def class_target(scene: Path, seed: int) -> tuple[str, str, str]:
    """The object a learned-detector pick chases on ``seed``: (scene object name, its detector class, its colour).
    One of the objects the seed puts on the table (the world's own draw: the scene's ``choose`` from the seed's
    object stream), the (seed mod their number)-th in file order, so the targets go round the classes."""
    from bt_grasp.detector.dataset import object_class
    from bt_grasp.scene.format import load_scene
    from bt_grasp.scene.layout import draw_layout
    from bt_grasp.seeds import RunSeeds, Stream

    config = load_scene(scene)
    stream = RunSeeds(int(seed)).generator(Stream.OBJECTS)  # the world's own draw of this seed
    drawn = draw_layout(config, stream).objects
    target = drawn[seed % len(drawn)]
    return target.name, object_class(target.shape, target.mesh, scene, target.name), str(target.color)


def _picked(run: EpisodeResult) -> str:
    """The object the judge names for a run (the one that rose most), or '(none)'."""
    return run.judged.object_name or "(none)"


def _outcome(run: EpisodeResult) -> str:
    if run.success:
        return f"picked {_picked(run)}"
    return f"FAILURE {_why(run)}"


def _why(run: EpisodeResult) -> str:
    """Why a run failed: the leaf's reason (if the tree failed) and the judge's first unmet condition."""
    parts = [f"{run.reason} ({run.failed_leaf})"] if run.tree_status != "SUCCESS" else ["tree SUCCESS"]
    failed = next(((c, d) for c, m, d in run.judged.conditions if not m), None)
    if failed is not None:
        parts.append(f"judge: {failed[0]}: {failed[1]}")
    return "; ".join(parts)


def _per_object(runs: list[EpisodeResult]) -> dict[str, ObjectFigures]:
    """Per object the judge names (the one that rose most): runs, successes, and each failure's reason."""
    out: dict[str, ObjectFigures] = {}
    for name in sorted({_picked(r) for r in runs}):
        mine = [r for r in runs if _picked(r) == name]
        out[name] = {
            "runs": len(mine),
            "successes": sum(r.success for r in mine),
            "failures": {r.seed: _why(r) for r in mine if not r.success},
            "failure_reasons": dict(Counter(str(r.reason) for r in mine if not r.success)),
        }
    return out
