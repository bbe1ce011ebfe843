"""One campaign worker: a warm episode backend plus what turns an episode's result into a results row."""

from __future__ import annotations

import enum
import logging
import os
import socket
import time
from collections.abc import Callable
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path

from bt_grasp.campaign.environment import environment
from bt_grasp.campaign.episode import EpisodeBackend
from bt_grasp.campaign.rows import ResultRow
from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.episode.result import EpisodeResult
from bt_grasp.files.output_files import check_output_file, make_output_folder
from bt_grasp.files.safe_path import file_component
from bt_grasp.process.numeric_threads import NUMERIC_ENV

log = logging.getLogger(__name__)

#: columns that depend on where and when an episode ran, not on its inputs: excluded when comparing runs
PLACE_COLUMNS = ("wall_time_s", "setup_wall_s", "episode_wall_s", "mcap", "environment", "worker", "finished_at")


#: environment of every worker process (set before it imports numpy). OpenBLAS's second thread spin-waits
#: after each small linear-algebra call: ~0.2 s of CPU per pick episode that does nothing (same wall time, same
#: fingerprint without it) but takes a core from the other workers. One thread each: 2 workers on 2 cores went
#: from 69.9 to 82.5 episodes/min, 1 worker from 45.7 to 50.8 (`bt-grasp bench eval --seeds 50`, idle).
#: The command line sets the same in its own process (``bt_grasp.process.numeric_threads``).
WORKER_ENV: dict[str, str] = dict(NUMERIC_ENV)


class KeepLogs(enum.StrEnum):
    """Which episodes keep their MCAP log."""

    FAILURES = "failures"
    ALL = "all"
    NONE = "none"


def log_path(log_dir: Path, episode: PlannedEpisode) -> Path:
    """Where an episode's kept log goes: one plain file name inside ``log_dir``, whatever the campaign file
    names its tree, scene or fault plan (``../x`` becomes ``_x-<hash>``: a name never leaves the folder)."""
    parts = (Path(episode.tree).stem, episode.scene, episode.fault_plan, f"seed{episode.seed}", episode.key)
    return log_dir / ("__".join(file_component(str(p)) for p in parts) + ".mcap")


def make_row(episode: PlannedEpisode, result: EpisodeResult, mcap: Path | None, episode_wall_s: float
             ) -> ResultRow:
    env = environment()
    return {
        "campaign": episode.campaign,
        "episode": episode.key,
        "index": episode.index,
        "tree": episode.tree,
        "scene": episode.scene,
        "seed": episode.seed,
        "fault_plan": episode.fault_plan,
        "params": episode.blackboard,
        "max_ticks": episode.max_ticks,
        "inputs_digest": episode.inputs_digest,
        "success": result.success,
        "judged_goal": result.goal.kind,
        "tree_status": result.tree_status,
        "failure_reason": result.reason,
        "failed_leaf": result.failed_leaf,
        "failed_path": result.failed_path,
        "retries": result.retries,
        "retries_total": sum(result.retries.values()),
        "faults_fired": result.faults_fired,
        "faults": [f.to_json() for f in result.faults],
        "ticks": result.ticks,
        "sim_time_s": round(result.sim_time_s, 6),
        "judge": result.judged.to_json(),
        "fingerprint": str(result.fingerprint),
        "wall_time_s": round(result.wall_time_s, 3),
        "setup_wall_s": round(result.setup_wall_s, 3),
        "episode_wall_s": round(episode_wall_s, 3),
        "mcap": str(mcap) if mcap is not None else None,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
        "finished_at": datetime.now(UTC).isoformat(timespec="seconds"),
        "environment": env,
    }


class Worker:
    """Runs episodes one after another on one backend, whose simulator and renderer stay warm."""

    def __init__(self, backend_factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs) -> None:
        self.backend = backend_factory()
        self.log_dir = Path(log_dir)
        self.keep_logs = KeepLogs(keep_logs)
        t0 = time.perf_counter()
        self.backend.warm_up()
        self.warm_up_s = time.perf_counter() - t0
        log.debug("worker %d warm in %.2f s", os.getpid(), self.warm_up_s)

    def run(self, episode: PlannedEpisode) -> ResultRow:
        """Run one episode; its fingerprint is computed as it runs. With ``--keep-logs all`` it is recorded as
        it runs; with ``failures`` a failed episode is run once more with a log (same seed, same run: the
        second run's fingerprint must equal the first's, else the row says so)."""
        t0 = time.perf_counter()
        path = log_path(self.log_dir, episode)
        make_output_folder(path.parent, "--out")
        check_output_file(path, "--out", example="x.mcap")  # a link planted at a kept log's name is not followed
        keep = self.keep_logs is KeepLogs.ALL
        result = self.backend.run(episode, path if keep else None)
        if not result.success and self.keep_logs is KeepLogs.FAILURES:
            again = self.backend.run(episode, path)
            keep = True
            if again.fingerprint != result.fingerprint:
                log.warning("%s: the run again with its log differs (fingerprint %s, then %s)", episode.key,
                            result.fingerprint, again.fingerprint)
                result = replace(result, fingerprint=f"{result.fingerprint} (its log's run: {again.fingerprint})")
        return make_row(episode, result, path if keep else None, time.perf_counter() - t0)
