"""Wrappers of the pipeline's planner and kinematics services that return their own failure statuses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.services import Planner
from bt_grasp.faults.armed import ArmedFault
from bt_grasp.faults.model import PlannerFailParams, ServiceFailParams
from bt_grasp.geometry import Mat4
from bt_grasp.motion.cartesian import CartesianResult
from bt_grasp.motion.collision import CollisionChecker
from bt_grasp.motion.kinematics import IKOptions, IKResult, IKStatus, KinematicModel
from bt_grasp.motion.planner import PlannerOptions, PlanResult, PlanStatus
from bt_grasp.motion.planning_scene import PlanningScene


class _FailingCalls:
    """Pending failing calls: each armed fault fails its ``calls`` next calls, the oldest first."""

    def __init__(self) -> None:
        self._pending: list[tuple[ArmedFault, list[int]]] = []

    def add(self, arming: ArmedFault, calls: int) -> None:
        self._pending.append((arming, [calls]))

    def take(self, method: str) -> ArmedFault | None:
        self._pending = [(e, n) for e, n in self._pending if not e.done]
        if not self._pending:
            return None
        arming, left = self._pending[0]
        left[0] -= 1
        arming.fire(effect=f"{method} failed", calls=arming.params_as(ServiceFailParams).calls)
        if left[0] <= 0:
            arming.finish()
        return arming


class FaultyPlanner:
    """The motion planner (a :class:`bt_grasp.behaviours.services.Planner`), but ``plan_to_pose``/
    ``plan_to_joints`` fail while a planner fault is armed; ``checker`` and ``straight_line`` are the real
    planner's."""

    def __init__(self, inner: Planner) -> None:
        self.inner = inner
        self.failing = _FailingCalls()

    def checker(self, scene: PlanningScene, margin_m: float) -> CollisionChecker:
        return self.inner.checker(scene, margin_m)

    def straight_line(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene
                      ) -> CartesianResult:
        return self.inner.straight_line(q_start, T_base_tcp_goal, scene)

    def _failure(self, arming: ArmedFault) -> PlanResult:
        status = PlanStatus(arming.params_as(PlannerFailParams).status)
        return PlanResult(status=status, message=f"injected fault '{arming.fault.label}'")

    def plan_to_pose(self, q_start: NDArray[np.float64], T_base_tcp_goal: Mat4, scene: PlanningScene,
                     options: PlannerOptions | None = None) -> PlanResult:
        arming = self.failing.take("plan_to_pose")
        if arming is not None:
            return self._failure(arming)
        return self.inner.plan_to_pose(q_start, T_base_tcp_goal, scene, options)

    def plan_to_joints(self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: PlanningScene,
                       options: PlannerOptions | None = None) -> PlanResult:
        arming = self.failing.take("plan_to_joints")
        if arming is not None:
            return self._failure(arming)
        return self.inner.plan_to_joints(q_start, q_goal, scene, options)


class FaultyKinematics:
    """The arm kinematics, but ``ik``/``ik_solutions`` find no solution while an IK fault is armed.

    Forward kinematics is never touched (it is arithmetic on measured joints, it does not fail).
    """

    def __init__(self, inner: KinematicModel) -> None:
        self.inner = inner
        self.failing = _FailingCalls()

    @property
    def opening_m(self) -> float:
        return self.inner.opening_m

    @property
    def urdf_path(self) -> Path:
        return self.inner.urdf_path

    def fk(self, q: NDArray[np.float64]) -> Mat4:
        return self.inner.fk(q)

    def fk_link(self, q: NDArray[np.float64], link: str) -> Mat4:
        return self.inner.fk_link(q, link)

    @staticmethod
    def _unreachable(q_current: NDArray[np.float64]) -> IKResult:
        q = np.asarray(q_current, dtype=float).reshape(-1).copy()
        return IKResult(IKStatus.UNREACHABLE, q, float("inf"), float("inf"), 0)

    def ik(self, T_base_tcp_goal: Mat4, q_current: NDArray[np.float64], *, seeds: int = 8,
           rng: np.random.Generator | None = None, options: IKOptions | None = None) -> IKResult:
        if self.failing.take("ik") is not None:
            return self._unreachable(q_current)
        return self.inner.ik(T_base_tcp_goal, q_current, seeds=seeds, rng=rng, options=options)

    def ik_solutions(
        self, T_base_tcp_goal: Mat4, q_current: NDArray[np.float64], *, seeds: int = 8,
        rng: np.random.Generator | None = None, options: IKOptions | None = None, max_solutions: int | None = None,
        stop_if_current_converges: bool = False,
    ) -> tuple[list[NDArray[np.float64]], IKResult]:
        if self.failing.take("ik_solutions") is not None:
            return [], self._unreachable(q_current)
        return self.inner.ik_solutions(T_base_tcp_goal, q_current, seeds=seeds, rng=rng, options=options,
                                       max_solutions=max_solutions,
                                       stop_if_current_converges=stop_if_current_converges)
