"""A stand-in episode backend for engine tests without the simulator: each episode sleeps a little and
returns a result that depends only on the episode's inputs (importable by spawned worker processes)."""

from __future__ import annotations

import time
from pathlib import Path

from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.episode.instruments import PlanningStats
from bt_grasp.episode.result import EpisodeResult, Judged
from bt_grasp.scene.goals import PickGoal


def stand_in_result(episode: PlannedEpisode, *, success: bool, fingerprint: str) -> EpisodeResult:
    goal = PickGoal(kind="pick", color="red")
    return EpisodeResult(
        success=success,
        tree_status="SUCCESS" if success else "FAILURE",
        reason=None if success else "NO_DETECTION",
        failed_leaf=None if success else "Perceive",
        ticks=100 + episode.seed,
        sim_time_s=1.0 + episode.seed / 100,
        wall_time_s=0.4,
        retries={},
        judged=Judged(goal=goal, success=success, failed_condition=None, conditions=()),
        log=None,
        seed=episode.seed,
        goal=goal,
        planning=PlanningStats(calls=0, pose_calls=0, wall_s=0.0),
        fingerprint=fingerprint,
    )


class StandInBackend:
    def warm_up(self) -> None:
        pass

    def run(self, episode: PlannedEpisode, log: Path | None) -> EpisodeResult:
        time.sleep(0.4)
        return stand_in_result(episode, success=episode.seed % 3 != 0, fingerprint=f"stand-in {episode.key}")


def stand_in() -> StandInBackend:
    return StandInBackend()


class EnvProbeBackend(StandInBackend):
    """Reports, as its fingerprint, how many threads the worker's environment gives OpenBLAS."""

    def run(self, episode: PlannedEpisode, log: Path | None) -> EpisodeResult:
        import os
        from dataclasses import replace

        result = super().run(episode, log)
        return replace(result, fingerprint=f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")


def env_probe() -> EnvProbeBackend:
    return EnvProbeBackend()
