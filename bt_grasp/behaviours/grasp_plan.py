"""A grasp together with the motion planned to reach it: what PlanGrasp hands to Approach on the blackboard.

PlanGrasp keeps a candidate only once its whole approach was found collision-free (the planned path to the
pre-grasp pose and the straight descent to the grasp pose); the path travels with the grasp so
Approach executes it instead of planning the same motion again. Approach plans anew only when the plan no
longer fits: the arm moved since (measured joints differ) or the scene it was planned in changed (other
detections on the blackboard).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4

if TYPE_CHECKING:  # perception's package import loads open3d: only the types are needed here
    from bt_grasp.perception.results import Detection, GraspCandidate

#: the arm counts as where a plan started while no joint is further than this from the plan's start
MOVED_RAD = 1e-3


@runtime_checkable
class GraspPose(Protocol):
    """Anything that says where the tool grasps: a GraspCandidate or a GraspPlan."""

    @property
    def T_base_tcp_grasp(self) -> Mat4: ...


@dataclass(frozen=True, eq=False)
class GraspPlan:
    """``candidate`` plus ``approach_path`` (N, 6): a collision-free joint path from ``q_start`` to the
    pre-grasp pose, planned among ``target`` and ``objects`` (the scene as perceived), and ``descent_path``
    (M, 6): the straight tool line from the approach's end down to the grasp pose, checked with the fingers
    open against the same scene (the target itself may be touched)."""

    candidate: GraspCandidate
    q_start: NDArray[np.float64]
    approach_path: NDArray[np.float64]
    target: Detection
    objects: tuple[Detection, ...]
    descent_path: NDArray[np.float64] | None = None

    # the grasp's poses, read the same way from a plan as from a candidate
    @property
    def T_base_tcp_grasp(self) -> Mat4:
        return self.candidate.T_base_tcp_grasp

    @property
    def T_base_tcp_pregrasp(self) -> Mat4:
        return self.candidate.T_base_tcp_pregrasp

    @property
    def width_m(self) -> float:
        return self.candidate.width_m

    def planned_in(self, target: Detection | None, objects: Sequence[Detection]) -> bool:
        """Whether the plan was made in this scene (the same detections)."""
        return target == self.target and tuple(objects) == self.objects

    def starts_at(self, q: NDArray[np.float64]) -> bool:
        """Whether the arm is (still) where the plan starts."""
        return bool(np.max(np.abs(np.asarray(q, dtype=float) - self.q_start)) <= MOVED_RAD)
