"""A stand-in episode backend for engine tests without the simulator: each episode sleeps a little and
returns an outcome that depends only on the episode's inputs (importable by spawned worker processes)."""

from __future__ import annotations

import time
from pathlib import Path

from bt_grasp.campaign.episode import EpisodeOutcome
from bt_grasp.campaign.spec import Episode


class StandInBackend:
    def warm_up(self) -> None:
        pass

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        time.sleep(0.4)
        ok = episode.seed % 3 != 0
        return EpisodeOutcome(
            success=ok,
            judged_goal="pick",
            tree_status="SUCCESS" if ok else "FAILURE",
            failure_reason=None if ok else "NO_DETECTION",
            failed_leaf=None if ok else "Perceive",
            ticks=100 + episode.seed,
            sim_time_s=1.0 + episode.seed / 100,
            wall_time_s=0.4,
            setup_wall_s=0.0,
            retries={},
            faults_fired=0,
            judge={},
            fingerprint=f"stand-in {episode.key}",
        )


def stand_in() -> StandInBackend:
    return StandInBackend()


class EnvProbeBackend(StandInBackend):
    """Reports, as its fingerprint, how many threads the worker's environment gives OpenBLAS."""

    def run(self, episode: Episode, log: Path | None) -> EpisodeOutcome:
        import os
        from dataclasses import replace

        outcome = super().run(episode, log)
        return replace(outcome, fingerprint=f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")


def env_probe() -> EnvProbeBackend:
    return EnvProbeBackend()
