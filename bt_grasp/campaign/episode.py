"""The seam between campaigns and the code that runs one episode (the session/episode API).

A campaign worker only needs: "run these inputs on my warm simulator and tell me what happened". That is
:class:`EpisodeBackend`; the composition of a run (world, tree, faults, recorder, judge) stays below it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.episode.result import EpisodeResult


class EpisodeBackend(Protocol):
    """Runs episodes one after another in this process, keeping what it can warm between them."""

    def warm_up(self) -> None:
        """Pay the one-time start-up (imports, renderer) before the first episode."""

    def run(self, planned: PlannedEpisode, log: Path | None) -> EpisodeResult:
        """Run one episode to the end, recording it to ``log`` when one is given; the run fingerprint is
        computed while it runs (the same digest its log would give)."""
        ...
