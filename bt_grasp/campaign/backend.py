"""The campaign workers' episode backend, on the episode API (:mod:`bt_grasp.episode`) with warm worlds.

:class:`~bt_grasp.episode.WarmWorlds` keeps the renderer warm for the worker process and builds every
episode's world afresh, so the renderer's start-up is paid once per worker and an episode gives the same run
as in a fresh process, whatever ran before it (tests/episode/test_warm_world.py; docs/campaigns.md says why a
world is not reset and reused).
"""

from __future__ import annotations

import time
from pathlib import Path

from bt_grasp.campaign.episode import EpisodeOutcome
from bt_grasp.campaign.spec import Episode


class WarmEpisodeBackend:
    """Implements :class:`bt_grasp.campaign.episode.EpisodeBackend`."""

    def __init__(self) -> None:
        from bt_grasp.episode import WarmWorlds

        self.worlds = WarmWorlds()

    def warm_up(self) -> None:
        # the leaves and the motion and perception stacks they use (the simulator comes with the first world)
        import bt_grasp.behaviours
        import bt_grasp.episode.episode  # noqa: F401

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        from bt_grasp.episode import Episode as EpisodeRun
        from bt_grasp.episode import EpisodeRequest

        request = EpisodeRequest(
            tree=episode.tree_file,
            scene=episode.scene_file,
            seed=episode.seed,
            goal=episode.goal,
            calibration=episode.calibration_file,
            log=log,
            max_ticks=episode.max_ticks,
            faults=episode.fault_file,
            inject=episode.inject,
            blackboard=episode.blackboard,
            argv=("bt-grasp", "eval", "run", episode.campaign, episode.key),
            fingerprint=True,
            leaves=episode.leaves,
        )
        t0 = time.perf_counter()
        prepared = EpisodeRun(request, self.worlds)
        setup_s = time.perf_counter() - t0
        result = prepared.run()
        judge = result.judged.to_json()
        return EpisodeOutcome(
            success=result.success,
            judged_goal=result.goal.kind,
            tree_status=result.tree_status,
            failure_reason=result.reason,
            failed_leaf=result.failed_leaf,
            failed_path=result.failed_path,
            ticks=result.ticks,
            sim_time_s=result.sim_time_s,
            wall_time_s=result.wall_time_s,
            setup_wall_s=setup_s,
            retries=result.retries,
            faults_fired=result.faults_fired,
            judge=judge,
            fingerprint=str(result.fingerprint),
        )


def warm_backend() -> WarmEpisodeBackend:
    return WarmEpisodeBackend()
