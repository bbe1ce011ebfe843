"""The campaign workers' episode backend, on the episode API (:mod:`bt_grasp.episode`) with warm worlds.

:class:`~bt_grasp.episode.WarmWorlds` keeps the renderer warm for the worker process and builds every
episode's world afresh, so the renderer's start-up is paid once per worker and an episode gives the same run
as in a fresh process, whatever ran before it (tests/episode/test_warm_world.py; docs/campaigns.md says why a
world is not reset and reused).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.campaign.spec import PlannedEpisode

if TYPE_CHECKING:
    from bt_grasp.episode.result import EpisodeResult


class WarmEpisodeBackend:
    """Implements :class:`bt_grasp.campaign.episode.EpisodeBackend`."""

    def __init__(self) -> None:
        # deferred: start-up time (the coordinator imports this class to hand it to workers; they build worlds)
        from bt_grasp.episode import WarmWorlds

        self.worlds = WarmWorlds()

    def warm_up(self) -> None:
        # the leaves and the motion and perception stacks they use (the simulator comes with the first world)
        import bt_grasp.behaviours  # deferred: start-up time (paid here, once per worker, on purpose)
        import bt_grasp.episode.episode  # noqa: F401  # deferred: start-up time (as above)

    def run(self, planned: PlannedEpisode, log: Path | None) -> EpisodeResult:
        from bt_grasp.episode import Episode  # deferred: start-up time (the coordinator never runs an episode)

        request = replace(planned.request, log=log, fingerprint=True,
                          argv=("bt-grasp", "eval", "run", planned.campaign, planned.key))
        t0 = time.perf_counter()
        prepared = Episode(request, self.worlds)
        setup_s = time.perf_counter() - t0
        return replace(prepared.run(), setup_wall_s=setup_s)


def warm_backend() -> WarmEpisodeBackend:
    return WarmEpisodeBackend()
