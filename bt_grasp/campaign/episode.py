"""The seam between campaigns and the code that runs one episode (the session/episode API).

A campaign worker only needs: "run these inputs on my warm simulator and tell me what happened". That is
:class:`EpisodeBackend`; the composition of a run (world, tree, faults, recorder, judge) stays below it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from bt_grasp.campaign.spec import Episode


@dataclass(frozen=True)
class FinalState:
    """What the run left behind, for the run fingerprint: the arm, the gripper, every object's pose."""

    q_rad: tuple[float, ...]
    gripper_width_m: float
    object_poses: dict[str, tuple[float, ...]]  # name -> (x, y, z, qw, qx, qy, qz), world frame (judge only)


@dataclass(frozen=True)
class EpisodeOutcome:
    """One finished episode as the backend saw it (the worker turns it into a results row)."""

    success: bool
    judged_goal: str  # what the judge checked ("pick", "clear", "tree", ...)
    tree_status: str
    failure_reason: str | None
    failed_leaf: str | None
    ticks: int
    sim_time_s: float
    wall_time_s: float  # ticking the tree
    setup_wall_s: float  # preparing the episode: inputs loaded, world built or reset, tree wired (to tick 1)
    retries: dict[str, int]
    faults_fired: int
    judge: dict[str, Any]
    stream: list[dict[str, Any]]  # per tick: node path -> status
    failures: list[dict[str, Any]]  # every leaf FAILURE with its reason, in order
    final: FinalState
    blackboard: dict[str, Any] = field(default_factory=dict)  # final values, as text


class EpisodeBackend(Protocol):
    """Runs episodes one after another in this process, keeping what it can warm between them."""

    def warm_up(self) -> None:
        """Pay the one-time start-up (imports, renderer) before the first episode."""

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        """Run one episode to the end; write its MCAP log to ``log`` when given."""
        ...
