"""The seam between campaigns and the code that runs one episode (the session/episode API).

A campaign worker only needs: "run these inputs on my warm simulator and tell me what happened". That is
:class:`EpisodeBackend`; the composition of a run (world, tree, faults, recorder, judge) stays below it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from bt_grasp.campaign.spec import Episode


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
    fingerprint: str  # the run fingerprint's digest (bt_grasp.recording.fingerprint)
    failed_path: str | None = None  # the failed leaf's path (its name in every output)


class EpisodeBackend(Protocol):
    """Runs episodes one after another in this process, keeping what it can warm between them."""

    def warm_up(self) -> None:
        """Pay the one-time start-up (imports, renderer) before the first episode."""

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        """Run one episode to the end, recording it to ``log`` when one is given; the run fingerprint is
        computed while it runs (the same digest its log would give)."""
        ...
