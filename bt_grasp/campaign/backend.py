"""The campaign workers' episode backend, on the episode API (:mod:`bt_grasp.episode`) with a warm world.

:class:`~bt_grasp.episode.WarmWorlds` keeps one simulator + renderer per worker and resets it for each
episode (objects drawn again from the seed, arm home, clock at 0), so the renderer's start-up is paid once
per worker. A reset world gives the same run as a world built fresh in a new process (checked episode by
episode in tests/campaign/test_campaign_sim.py); a second world built beside a first one in the same
process did not (see docs/campaigns.md), which is why workers reset rather than rebuild.
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
