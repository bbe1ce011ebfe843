"""SIGINT/SIGTERM handling that lets a recorder finish its file (footer, summary) before the process ends.

The handler turns SIGTERM into ``SystemExit(128 + 15)`` and SIGINT into ``KeyboardInterrupt``, so the stack
unwinds through the recorder's ``__exit__``, which writes the summary. A signal that arrives while the
recorder is in the middle of writing a record is held until that record is complete, so the file never ends
in a half-written chunk. A signal stays pending until the recorder acknowledges it on the way out: if the
exception the handler raised is swallowed (a handler runs between any two bytecodes, finalizers included, and
Python ignores exceptions raised in ``__del__``), the next record written raises it again.
"""

from __future__ import annotations

import logging
import signal
import threading
from collections.abc import Callable
from types import FrameType

log = logging.getLogger(__name__)

_HANDLED = (signal.SIGINT, signal.SIGTERM)


def _interrupt_for(signum: int) -> BaseException:
    if signum == signal.SIGINT:
        return KeyboardInterrupt()
    return SystemExit(128 + signum)


class SignalGuard:
    """Installs the handlers while active; ``busy()`` marks a critical section that signals must not cut."""

    def __init__(self) -> None:
        self._previous: dict[int, Callable[[int, FrameType | None], object] | int | None] = {}
        self._busy = 0
        self._pending: int | None = None
        self._section = _Busy(self)

    @property
    def installed(self) -> bool:
        return bool(self._previous)

    def install(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            log.debug("not on the main thread: signals are left to their current handlers")
            return
        for signum in _HANDLED:
            current = signal.getsignal(signum)
            if current not in (signal.SIG_DFL, signal.default_int_handler):
                continue  # someone (a CLI, pytest) chose a handler on purpose: keep it
            self._previous[signum] = current
            signal.signal(signum, self._handle)

    def uninstall(self) -> None:
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)
        self._previous.clear()

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        self._pending = signum
        if not self._busy:
            raise _interrupt_for(signum)

    def acknowledge(self) -> None:
        """The interruption reached its destination (the recorder is closing): stop raising it."""
        self._pending = None

    def busy(self) -> _Busy:
        """A critical section (``with guard.busy(): ...``): a signal arriving inside is raised at its end."""
        return self._section

    def _enter(self) -> None:
        self._busy += 1

    def _leave(self) -> None:
        self._busy -= 1
        if not self._busy and self._pending is not None:
            raise _interrupt_for(self._pending)


class _Busy:
    """``SignalGuard.busy()``'s context manager: one object per guard, entered many times a tick (a plain
    class: a generator-based context manager cost a few microseconds each time)."""

    __slots__ = ("_guard",)

    def __init__(self, guard: SignalGuard) -> None:
        self._guard = guard

    def __enter__(self) -> None:
        self._guard._enter()

    def __exit__(self, *exc: object) -> None:
        self._guard._leave()
