"""The twin's clock: one controller cycle per period of the wall clock, on its own thread.

This is the one place the twin reads wall time to pace itself (a twin is a controller: it runs in real time;
the rest of bt_grasp stays on simulated time). Cycles are scheduled on absolute deadlines, so a late cycle does
not shift the next; a cycle more than a period late is counted as an overrun and the schedule restarts from now
(the physics then falls behind the wall clock by that much, and RTDE's ``timestamp`` says so).

Like a robot controller's, the thread asks the operating system for real-time scheduling (``SCHED_FIFO`` at a
low priority): a cycle then starts on time even when other programs keep every core busy. It needs the
permission (root, or ``CAP_SYS_NICE``/an ``RLIMIT_RTPRIO``); without it the twin says so once and runs at normal
priority, its period then as good as the machine's load allows (docs/twin.md has both figures).
"""

from __future__ import annotations

import itertools
import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable

log = logging.getLogger(__name__)


def ask_for_realtime(priority: int | None, what: str) -> bool:
    """Put the calling thread (only) on ``SCHED_FIFO`` at ``priority``; False, with one logged sentence, if the
    system refuses (None or 0: do not ask)."""
    if not priority or not hasattr(os, "SCHED_FIFO"):
        return False
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))  # pid 0: the calling thread
    except OSError as exc:
        log.warning("%s runs at normal priority: real-time scheduling was refused (%s); its timing will suffer "
                    "when the machine is busy", what, exc.strerror or exc)
        return False
    log.info("%s runs with real-time scheduling (SCHED_FIFO %d)", what, priority)
    return True


class RealtimeLoop:
    """Calls ``cycle()`` every ``period_s`` of wall time until :meth:`stop`."""

    def __init__(self, period_s: float, cycle: Callable[[], None], keep: int = 4096,
                 realtime_priority: int | None = 10) -> None:
        self.period_s = period_s
        self.realtime_priority = realtime_priority
        self.realtime = False
        self._cycle = cycle
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="twin-controller", daemon=True)
        self.overruns = 0
        self.cycles = 0
        #: the last ``keep`` cycles' start times (perf_counter seconds) and compute times (seconds)
        self.starts: deque[float] = deque(maxlen=keep)
        self.compute_s: deque[float] = deque(maxlen=keep)
        self.error: BaseException | None = None

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=2.0)

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    def _run(self) -> None:
        self.realtime = ask_for_realtime(self.realtime_priority, "the controller's cycle")
        period = self.period_s
        deadline = time.perf_counter()
        while not self._stop.is_set():
            now = time.perf_counter()
            if now < deadline:
                time.sleep(deadline - now)
                now = time.perf_counter()
            elif now - deadline > period:
                self.overruns += 1
                deadline = now
            self.starts.append(now)
            try:
                self._cycle()
            except BaseException as exc:  # the controller died: say so once, stop serving motion
                self.error = exc
                log.exception("the twin's controller cycle failed; the twin stops")
                return
            self.compute_s.append(time.perf_counter() - now)
            self.cycles += 1
            deadline += period

    def period_stats(self) -> dict[str, float]:
        """Percentiles of the measured period and compute time over the kept cycles (milliseconds)."""
        starts = list(self.starts)
        periods = sorted(b - a for a, b in itertools.pairwise(starts))
        compute = sorted(self.compute_s)

        def pct(values: list[float], q: float) -> float:
            return values[min(len(values) - 1, int(q * len(values)))] * 1000.0 if values else 0.0

        return {"period_p50_ms": pct(periods, 0.5), "period_p99_ms": pct(periods, 0.99),
                "period_max_ms": periods[-1] * 1000.0 if periods else 0.0,
                "compute_p50_ms": pct(compute, 0.5), "compute_p99_ms": pct(compute, 0.99),
                "overruns": float(self.overruns), "cycles": float(self.cycles)}
