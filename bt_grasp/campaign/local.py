"""Episodes on N local worker processes (``concurrent.futures``), each with one warm :class:`Worker`."""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from bt_grasp.campaign.episode import EpisodeBackend
from bt_grasp.campaign.runner import EpisodeError
from bt_grasp.campaign.spec import Episode
from bt_grasp.campaign.worker import WORKER_ENV, KeepLogs, Worker

log = logging.getLogger(__name__)

_WORKER: Worker | None = None  # this worker process's warm worker (set by the pool's initializer)


def _init(factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs) -> None:
    global _WORKER
    # Ctrl-C is the coordinator's to handle: it stops the pool; a worker must not die half-way on its own
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # the episodes' library logs are not the terminal's (the coordinator prints progress)
    logging.getLogger().addHandler(logging.NullHandler())
    _WORKER = Worker(factory, log_dir, keep_logs)


def _run(episode: Episode) -> dict[str, Any]:
    assert _WORKER is not None, "worker process not initialised"
    return _WORKER.run(episode)


def default_workers() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


class LocalEngine:
    """``workers`` processes (spawned, so no simulator state is inherited), episodes handed out as they free up."""

    def __init__(
        self, workers: int, backend_factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs
    ) -> None:
        self.workers = max(1, workers)
        self.backend_factory = backend_factory
        self.log_dir = log_dir
        self.keep_logs = keep_logs

    def run(self, episodes: Sequence[Episode]) -> Iterator[dict[str, Any] | EpisodeError]:
        for key, value in WORKER_ENV.items():  # spawned workers inherit it before they import numpy
            os.environ.setdefault(key, value)
        pool = ProcessPoolExecutor(
            max_workers=min(self.workers, len(episodes)),
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init,
            initargs=(self.backend_factory, self.log_dir, self.keep_logs),
        )
        futures: dict[Future[dict[str, Any]], Episode] = {pool.submit(_run, e): e for e in episodes}
        open_futures = set(futures)
        try:
            while open_futures:
                finished, open_futures = wait(open_futures, return_when=FIRST_COMPLETED)
                # finished rows first: a broken pool must not hide a row that did finish
                for fut in sorted(finished, key=lambda f: f.exception() is not None):
                    exc = fut.exception()
                    if exc is None:
                        yield fut.result()
                    else:
                        lost = isinstance(exc, BrokenProcessPool)
                        yield EpisodeError(futures[fut], f"{type(exc).__name__}: {exc}", worker_lost=lost)
        except BaseException:
            _stop(pool)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Stop the workers now (Ctrl-C): running episodes are dropped and run again on resume."""
    pool.shutdown(wait=False, cancel_futures=True)
    # Python 3.11's executor has no public way to end busy workers (3.14 adds terminate_workers())
    for process in list(getattr(pool, "_processes", {}).values()):
        if process.is_alive():
            process.terminate()
