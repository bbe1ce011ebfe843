"""Wrappers of the pipeline's planner and kinematics services that return their own failure statuses."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.faults.episode import Episode
from bt_grasp.motion.kinematics import IKResult, IKStatus
from bt_grasp.motion.planner import PlanResult, PlanStatus


class _FailingCalls:
    """Pending failing calls: each armed episode fails its ``calls`` next calls, oldest episode first."""

    def __init__(self) -> None:
        self._pending: list[tuple[Episode, list[int]]] = []

    def add(self, episode: Episode, calls: int) -> None:
        self._pending.append((episode, [calls]))

    def take(self, method: str) -> Episode | None:
        self._pending = [(e, n) for e, n in self._pending if not e.done]
        if not self._pending:
            return None
        episode, left = self._pending[0]
        left[0] -= 1
        episode.fire(effect=f"{method} failed", calls=episode.params.calls)
        if left[0] <= 0:
            episode.finish()
        return episode


class FaultyPlanner:
    """The motion planner, but ``plan_to_pose``/``plan_to_joints`` fail while a planner fault is armed."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.failing = _FailingCalls()

    def __getattr__(self, name: str) -> Any:  # checker(), options, ...: the real planner's
        return getattr(self.inner, name)

    def _failure(self, episode: Episode) -> PlanResult:
        status = PlanStatus(episode.params.status)
        return PlanResult(status=status, message=f"injected fault '{episode.fault.label}'")

    def plan_to_pose(self, *args: Any, **kwargs: Any) -> PlanResult:
        episode = self.failing.take("plan_to_pose")
        return self._failure(episode) if episode is not None else self.inner.plan_to_pose(*args, **kwargs)

    def plan_to_joints(self, *args: Any, **kwargs: Any) -> PlanResult:
        episode = self.failing.take("plan_to_joints")
        return self._failure(episode) if episode is not None else self.inner.plan_to_joints(*args, **kwargs)


class FaultyKinematics:
    """The arm kinematics, but ``ik``/``ik_solutions`` find no solution while an IK fault is armed.

    Forward kinematics is never touched (it is arithmetic on measured joints, it does not fail).
    """

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.failing = _FailingCalls()

    def __getattr__(self, name: str) -> Any:  # fk, fk_link, limits, ...: the real model's
        return getattr(self.inner, name)

    @staticmethod
    def _unreachable(q_current: NDArray[np.float64]) -> IKResult:
        q = np.asarray(q_current, dtype=float).reshape(-1).copy()
        return IKResult(IKStatus.UNREACHABLE, q, float("inf"), float("inf"), 0)

    def ik(self, T_base_tcp_goal: Any, q_current: NDArray[np.float64], **kwargs: Any) -> IKResult:
        if self.failing.take("ik") is not None:
            return self._unreachable(q_current)
        result: IKResult = self.inner.ik(T_base_tcp_goal, q_current, **kwargs)
        return result

    def ik_solutions(
        self, T_base_tcp_goal: Any, q_current: NDArray[np.float64], **kwargs: Any
    ) -> tuple[list[NDArray[np.float64]], IKResult]:
        if self.failing.take("ik_solutions") is not None:
            return [], self._unreachable(q_current)
        result: tuple[list[NDArray[np.float64]], IKResult] = self.inner.ik_solutions(
            T_base_tcp_goal, q_current, **kwargs
        )
        return result
