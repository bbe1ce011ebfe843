"""How one episode ended: the tree's view, the judge's verdict, and where its log is."""

from __future__ import annotations

from dataclasses import dataclass, field

from bt_grasp.episode.instruments import PlanningStats
from bt_grasp.faults.firing import FaultFiring
from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.scene.goals import Goal


def goal_json(goal: Goal) -> JsonObject:
    """The goal as the scene file would write it (``kind`` plus its fields)."""
    return {key: value for key, value in goal.model_dump(mode="json").items()}


@dataclass(frozen=True)
class Judged:
    """The judge's verdict as plain data (from ``bt_grasp.sim.judge.Verdict``): ground truth, judge only."""

    goal: Goal
    success: bool
    failed_condition: str | None  # the first condition not met (a ``Criterion`` value), None on success
    conditions: tuple[tuple[str, bool, str], ...]  # (criterion, met, what was measured)
    object_name: str | None = None
    object_lift_m: float = 0.0
    in_gripper: bool = False
    lifted_objects: tuple[str, ...] = ()
    objects_in_workspace: tuple[str, ...] = ()
    #: every object's final T_world_object (4x4): the end of the run's fingerprint (recording/fingerprint.py)
    object_poses: dict[str, list[list[float]]] = field(default_factory=dict)
    #: who judged: the simulator's judge (a simulated run), the twin's physics judge, or a real cell's own checks
    source: str = "simulator ground truth (judge only)"

    def to_json(self) -> JsonObject:
        poses: dict[str, JsonValue] = {n: [list(row) for row in T] for n, T in self.object_poses.items()}
        return {
            "source": self.source,
            "goal": goal_json(self.goal),
            "task": self.goal.kind,
            "success": self.success,
            "failed_condition": self.failed_condition,
            "conditions": [{"criterion": c, "met": m, "detail": d} for c, m, d in self.conditions],
            "object": self.object_name,
            "in_gripper": self.in_gripper,
            "lifted_objects": list(self.lifted_objects),
            "objects_in_workspace": list(self.objects_in_workspace),
            "object_poses": poses,
        }


@dataclass(frozen=True)
class ChainStep:
    """One link of the causal chain of a run's failures: a leaf FAILURE that was not by design (a condition
    asked by a Fallback is not one), its reason, and what followed it (a retry, the end of the run)."""

    tick: int
    sim_time_s: float
    leaf_path: str
    reason: str | None
    followed: str

    def to_json(self) -> JsonObject:
        return {"tick": self.tick, "sim_time_s": round(self.sim_time_s, 3), "leaf_path": self.leaf_path,
                "reason": self.reason, "followed": self.followed}


@dataclass(frozen=True)
class EpisodeResult:
    """``success``: the goal judged met by physics AND the tree returned SUCCESS.

    ``reason``/``failed_leaf``: the last leaf FAILURE when the tree failed (or ``MAX_TICKS`` when the tick limit
    ran out); ``GOAL_NOT_MET`` and no leaf when the tree succeeded but the goal was not met (the judge's first
    unmet condition, ``judged.failed_condition``, says why).
    ``failed_path``: that leaf's path, its one name in every output (``tree show``, logs, replay, reports).
    """

    success: bool
    tree_status: str  # SUCCESS, FAILURE, or RUNNING when max_ticks ran out
    reason: str | None
    failed_leaf: str | None
    ticks: int
    sim_time_s: float
    wall_time_s: float
    retries: dict[str, int]
    judged: Judged
    log: str | None
    seed: int
    goal: Goal
    planning: PlanningStats
    faults_fired: int = 0
    #: the run fingerprint's digest (``bt_grasp.recording.fingerprint``) when the request asked for it: the
    #: same digest ``fingerprint_of_log`` gives for this run's log
    fingerprint: str | None = None
    failed_path: str | None = None
    #: every leaf FAILURE that was not by design, in order, with what followed it (the run summary's last lines)
    failure_chain: tuple[ChainStep, ...] = ()
    #: the verdicts on the request's ``also_judge`` goals, in order (they decide nothing)
    also_judged: tuple[Judged, ...] = ()
    #: every fault that fired, in order: when, armed by which leaf, the object a push hit and whether the tree
    #: ever touched it (``FaultFiring.missed``: a fault that tested nothing the tree did)
    faults: tuple[FaultFiring, ...] = ()
    #: wall time spent preparing the episode (inputs loaded, world built, tree wired) before its first tick;
    #: set by whoever prepared it (a campaign worker), 0 when nobody measured it. Not in ``to_json``: the log's
    #: result holds no wall-clock figure of preparation.
    setup_wall_s: float = 0.0

    @property
    def object_lift_m(self) -> float:
        return self.judged.object_lift_m

    def unmet(self) -> tuple[str, str] | None:
        """The goal's first unmet condition and what the judge measured (None when the goal was met)."""
        return next(((c, d) for c, met, d in self.judged.conditions if not met), None)

    def to_json(self) -> JsonObject:
        retries: dict[str, JsonValue] = {k: v for k, v in self.retries.items()}
        out: JsonObject = {
            "success": self.success,
            "tree_status": self.tree_status,
            "reason": self.reason,
            "failed_leaf": self.failed_leaf,
            "failed_path": self.failed_path,
            "failure_chain": [step.to_json() for step in self.failure_chain],
            "ticks": self.ticks,
            "sim_time_s": round(self.sim_time_s, 3),
            "wall_time_s": round(self.wall_time_s, 3),
            "retries": retries,
            "object_lift_m": round(self.judged.object_lift_m, 4),
            "goal": goal_json(self.goal),
            "judge": self.judged.to_json(),
            "log": self.log,
            "seed": self.seed,
            "faults_fired": self.faults_fired,
            "planning": {k: v for k, v in self.planning.to_json().items()},
        }
        if self.faults:  # only when one fired: a run without faults records what it always did
            out["faults"] = [f.to_json() for f in self.faults]
        return out


#: ``reason`` of a run a Ctrl-C ended (its result is not judged: ``success`` is null)
INTERRUPTED = "INTERRUPTED"
#: ``reason`` of a run whose tree succeeded and whose goal was not met (``judged.failed_condition`` says which
#: condition; no leaf is blamed: the failures the tree recovered from are in ``failure_chain``)
GOAL_NOT_MET = "GOAL_NOT_MET"


def interrupted_result(tick: int, now_ns: int, seed: int) -> JsonObject:
    """The result a run ended by Ctrl-C records before its log is finished: not judged (``success`` null),
    ``interrupted`` true, and the tick and simulated time it stopped at (replay and the report say so)."""
    return {
        "success": None,
        "interrupted": True,
        "tree_status": "RUNNING",
        "reason": INTERRUPTED,
        "failed_leaf": None,
        "failed_path": None,
        "ticks": tick,
        "sim_time_s": round(now_ns * 1e-9, 3),
        "seed": seed,
    }
