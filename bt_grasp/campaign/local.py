"""Episodes on N local worker processes (``concurrent.futures``), each with one warm :class:`Worker`."""

from __future__ import annotations

import atexit
import ctypes
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from bt_grasp.campaign.episode import EpisodeBackend
from bt_grasp.campaign.rows import ResultRow
from bt_grasp.campaign.runner import EpisodeError
from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.campaign.worker import WORKER_ENV, KeepLogs, Worker

log = logging.getLogger(__name__)

_WORKER: Worker | None = None  # this worker process's warm worker (set by the pool's initializer)

#: how often a worker's watchdog checks that its coordinator is still its parent (seconds)
PARENT_POLL_S = 1.0
_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def _init(factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs, coordinator: int,
          kernel_signal: bool, poll_s: float) -> None:
    global _WORKER
    tie_to_coordinator(coordinator, kernel_signal, poll_s)
    # Ctrl-C is the coordinator's to handle: it stops the pool; a worker must not die half-way on its own
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # the episodes' library logs are not the terminal's (the coordinator prints progress)
    logging.getLogger().addHandler(logging.NullHandler())
    _WORKER = Worker(factory, log_dir, keep_logs)
    atexit.register(_exit_quietly)


def _exit_quietly() -> None:
    """Leave before the interpreter's teardown, where nanobind (OMPL's bindings) prints a hundred "leaked ..."
    lines into the user's terminal at every worker's end (the coordinator leaves the same way, in ``cli.main``).
    Registered last, so called first: it runs every other exit handler itself (idle log writers closed,
    temporary folders removed), as a normal exit would, then ends the process. A spawned worker's exit code is
    not read by the pool (a lost worker is seen by its sentinel), so 0 is kept."""
    atexit.unregister(_exit_quietly)
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def tie_to_coordinator(coordinator: int, kernel_signal: bool, poll_s: float = PARENT_POLL_S) -> None:
    """End this worker process when its coordinator (pid ``coordinator``, its parent) ends, however it ends: a
    coordinator killed with SIGKILL cannot stop its pool, and a worker (~700 MB with a warm simulator) would wait
    for episodes forever (it holds both ends of the pool's pipes, so it never sees them close).

    - ``kernel_signal``: Linux's ``PR_SET_PDEATHSIG`` has the kernel send SIGKILL the moment the parent goes.
      The kernel's "parent" is the *thread* that spawned this process, so the coordinator asks for it only when
      it spawned its workers from its main thread (which outlives every other one of its threads).
    - then, if the parent is already not the coordinator, it died before the request: exit now.
    - always, a watchdog thread compares ``os.getppid()`` with the coordinator every ``poll_s`` (an orphan is
      re-parented): the fallback without the kernel's signal (another thread spawned us, not Linux)."""
    if kernel_signal and sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            log.warning("prctl(PR_SET_PDEATHSIG) failed (errno %d); the watchdog alone ties this worker to its "
                        "coordinator", ctypes.get_errno())
    if os.getppid() != coordinator:
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(coordinator, poll_s), name="coordinator-watchdog",
                     daemon=True).start()


def _watch_parent(coordinator: int, poll_s: float) -> None:
    while True:
        time.sleep(poll_s)  # a lifetime check, not a decision of any run
        if os.getppid() != coordinator:
            os._exit(1)


def _run(episode: PlannedEpisode) -> ResultRow:
    assert _WORKER is not None, "worker process not initialised"
    return _WORKER.run(episode)


def default_workers() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


class LocalEngine:
    """``workers`` processes (spawned, so no simulator state is inherited), episodes handed out as they free up.
    The workers end with the coordinator process, even a SIGKILLed one (:func:`tie_to_coordinator`)."""

    def __init__(
        self, workers: int, backend_factory: Callable[[], EpisodeBackend], log_dir: Path, keep_logs: KeepLogs
    ) -> None:
        self.workers = max(1, workers)
        self.backend_factory = backend_factory
        self.log_dir = log_dir
        self.keep_logs = keep_logs

    def run(self, episodes: Sequence[PlannedEpisode]) -> Iterator[ResultRow | EpisodeError]:
        for key, value in WORKER_ENV.items():  # spawned workers inherit it before they import numpy
            os.environ.setdefault(key, value)
        # every worker is spawned by the submit() calls below, in this thread (Python 3.11's pool spawns again
        # only to replace a worker that ended by max_tasks_per_child, which is not used: a lost worker breaks it)
        in_main_thread = threading.current_thread() is threading.main_thread()
        pool = ProcessPoolExecutor(
            max_workers=min(self.workers, len(episodes)),
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init,
            initargs=(self.backend_factory, self.log_dir, self.keep_logs, os.getpid(), in_main_thread,
                      PARENT_POLL_S),
        )
        futures: dict[Future[ResultRow], PlannedEpisode] = {pool.submit(_run, e): e for e in episodes}
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
