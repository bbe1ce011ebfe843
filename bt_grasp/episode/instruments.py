"""Measuring a run through its seams: a planner wrapper that counts calls and their computing time.

Wall time here is reported only (benchmarks, the run summary); no decision of the run reads it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # motion loads pinocchio and ompl, numpy ~0.1 s (the resident's client): only types needed here
    import numpy as np
    from numpy.typing import NDArray

    from bt_grasp.behaviours.services import Planner
    from bt_grasp.geometry import Mat4
    from bt_grasp.motion.cartesian import CartesianResult
    from bt_grasp.motion.collision import CollisionChecker
    from bt_grasp.motion.planner import PlannerOptions, PlanResult
    from bt_grasp.motion.planning_scene import PlanningScene


@dataclass(frozen=True)
class PlanningStats:
    """How much motion planning one episode did (joint-space plans; Cartesian segments are not counted)."""

    calls: int  # plan_to_pose + plan_to_joints
    pose_calls: int  # plan_to_pose alone (IK + plan: approaches, MoveAbove)
    wall_s: float  # computing time of those calls on this machine

    def to_json(self) -> dict[str, int | float]:
        return {"calls": self.calls, "pose_calls": self.pose_calls, "wall_s": round(self.wall_s, 4)}


class TimedPlanner:
    """A :class:`Planner` that passes every call on and keeps count (installed by the episode)."""

    def __init__(self, inner: Planner) -> None:
        self.inner = inner
        self.calls = 0
        self.pose_calls = 0
        self.wall_s = 0.0

    def stats(self) -> PlanningStats:
        return PlanningStats(self.calls, self.pose_calls, self.wall_s)

    def checker(self, scene: PlanningScene, margin_m: float) -> CollisionChecker:
        return self.inner.checker(scene, margin_m)

    def straight_line(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene
                      ) -> CartesianResult:
        return self.inner.straight_line(q_start, T_base_tcp_goal, scene)

    def plan_to_pose(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                     options: PlannerOptions | None = None) -> PlanResult:
        t0 = time.perf_counter()
        try:
            return self.inner.plan_to_pose(q_start, T_base_tcp_goal, scene, options)
        finally:
            self.calls += 1
            self.pose_calls += 1
            self.wall_s += time.perf_counter() - t0

    def plan_to_joints(self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: PlanningScene,
                       options: PlannerOptions | None = None) -> PlanResult:
        t0 = time.perf_counter()
        try:
            return self.inner.plan_to_joints(q_start, q_goal, scene, options)
        finally:
            self.calls += 1
            self.wall_s += time.perf_counter() - t0
