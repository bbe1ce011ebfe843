"""The resident episode process: accepts requests on a Unix socket and runs episodes warm, one at a time.

Each episode runs in a thread of its own, under a deadline (:func:`request_deadline_s`: generous for its tick
limit, and bounded): a request that never finishes (a plugin that hangs, a file that blocks a reader) cannot wedge
the process. At the deadline the waiting client is told so, and the resident exits (a thread cannot be stopped
from outside; the next client starts a fresh resident). Meanwhile the accepting thread keeps answering: ``status``
and ``stop`` work while an episode runs (``stop`` ends the process at once), and further episode requests wait for
their turn (each connection still has 15 s to prove its key and send its request)."""

from __future__ import annotations

import contextlib
import fcntl
import logging
import os
import sys
import threading
import time
import traceback
from multiprocessing.connection import Listener
from typing import Any

from bt_grasp.errors import BtGraspError
from bt_grasp.resident.protocol import (
    IDLE_TIMEOUT_S,
    authkey,
    code_version,
    lock_path,
    request_adapter,
    result_adapter,
    socket_path,
)
from bt_grasp.resident.wire import WireError, deadline, receive, send, server_handshake

log = logging.getLogger(__name__)

#: how long a client may take to prove it knows the key, then to send its request, and both together (a peer
#: that sends half a frame or trickles bytes is cut off at the total)
HANDSHAKE_TIMEOUT_S = 5.0
REQUEST_TIMEOUT_S = 10.0
CONNECTION_DEADLINE_S = HANDSHAKE_TIMEOUT_S + REQUEST_TIMEOUT_S
#: how long a starting resident waits for the folder's lock before leaving it to the process that holds it
LOCK_WAIT_S = 3.0
#: an episode request's deadline: this much, plus this much per tick of its tick limit (a 12,000-tick episode gets
#: 100 minutes; a loaded 2-core machine runs 5-20 ticks a second), at most MAX_DEADLINE_S;
#: ``BT_GRASP_RESIDENT_DEADLINE_S`` sets one deadline for every request instead
DEADLINE_BASE_S = 300.0
DEADLINE_PER_TICK_S = 0.5
MAX_DEADLINE_S = 6 * 3600.0
DEADLINE_ENV = "BT_GRASP_RESIDENT_DEADLINE_S"


def _watchdog(state: dict[str, float], idle_s: float) -> None:
    while True:
        time.sleep(min(5.0, idle_s))
        if not state["busy"] and time.monotonic() - state["last"] > idle_s:
            socket_path().unlink(missing_ok=True)
            os._exit(0)


def request_deadline_s(max_ticks: int) -> float:
    """How long one episode request may take (see :data:`DEADLINE_BASE_S`)."""
    fixed = os.environ.get(DEADLINE_ENV, "")
    try:
        if fixed and float(fixed) > 0:
            return min(float(fixed), MAX_DEADLINE_S)
    except ValueError:
        pass
    return min(DEADLINE_BASE_S + DEADLINE_PER_TICK_S * max(0, max_ticks), MAX_DEADLINE_S)


def _handle(message: dict[str, Any], worlds: Any, version: str) -> tuple[str, dict[str, Any]]:
    """The reply (kind, fields) to one episode request; a request that does not validate is an ``error`` reply."""
    kind = message["kind"]
    if kind != "run":
        return "error", {"message": f"unknown request {kind[:40]!r}", "exit_code": 2}
    if message.get("code_version") != version:
        return "stale", {"code_version": version}
    from pydantic import ValidationError

    from bt_grasp.episode import EpisodeRequest, run_episode  # deferred: loads in the resident, on a request

    try:
        request = request_adapter().validate_python(message.get("request"))
    except ValidationError as exc:
        return "error", {"message": f"malformed episode request ({exc.error_count()} problem(s))", "exit_code": 2}
    try:
        result = run_episode(request, worlds=worlds)
    except BtGraspError as exc:
        return "error", {"message": str(exc), "exit_code": exc.exit_code}
    except Exception:
        return "crash", {"message": traceback.format_exc()}
    assert isinstance(request, EpisodeRequest)
    return "ok", {"result": result_adapter().dump_python(result, mode="json"), "pid": os.getpid()}


def _hold_the_lock() -> int | None:
    """This folder's resident lock, or None when another resident process holds it (then this one is not
    needed: two cold clients may both start one, and the second one to get here simply leaves)."""
    fd = os.open(lock_path(), os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
    deadline = time.monotonic() + LOCK_WAIT_S  # a resident that said "stale" is exiting: give it a moment
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            break
        except BlockingIOError:
            if time.monotonic() > deadline:
                os.close(fd)
                return None
            time.sleep(0.05)
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    return fd  # kept open for the process's life; the kernel releases the lock however it ends


def _max_ticks(message: dict[str, Any]) -> int:
    request = message.get("request")
    value = request.get("max_ticks") if isinstance(request, dict) else None
    return value if isinstance(value, int) and not isinstance(value, bool) else 0


class _Runner:
    """Runs episode requests one at a time, each in its own thread under its deadline (see the module)."""

    def __init__(self, worlds: Any, version: str, state: dict[str, float]) -> None:
        self.worlds, self.version, self.state = worlds, version, state
        self.turn = threading.Lock()  # one episode at a time; later requests wait in their threads
        self.waiting = 0
        self.count = threading.Lock()

    def start(self, conn: Any, message: dict[str, Any]) -> None:
        with self.count:
            self.waiting += 1
            self.state["busy"] = 1.0
        threading.Thread(target=self._run, args=(conn, message), daemon=True).start()

    def _run(self, conn: Any, message: dict[str, Any]) -> None:
        stop = False
        try:
            with self.turn:
                finished = threading.Event()
                seconds = request_deadline_s(_max_ticks(message))
                watchdog = threading.Thread(target=self._watch, args=(conn, finished, seconds), daemon=True)
                watchdog.start()
                try:
                    kind, fields = _handle(message, self.worlds, self.version)
                finally:
                    finished.set()
                send(conn, kind, **fields)
                stop = kind == "stale"  # the code changed under it
        except (WireError, OSError, EOFError) as exc:
            log.warning("dropped a connection: %s", exc)
        except Exception:  # whatever one request does, the resident goes on serving the others
            log.exception("dropped a connection")
        finally:
            conn.close()
            with self.count:
                self.waiting -= 1
                self.state["busy"] = float(self.waiting > 0)
                self.state["last"] = time.monotonic()
        if stop:
            socket_path().unlink(missing_ok=True)
            os._exit(0)

    def _watch(self, conn: Any, finished: threading.Event, seconds: float) -> None:
        if finished.wait(seconds):
            return
        log.error("an episode request did not finish within %.0f s; the resident process exits", seconds)
        with contextlib.suppress(Exception):  # the client is told why, if it still listens
            send(conn, "error", message=f"the episode did not finish within the resident's deadline of {seconds:.0f} "
                 "s (see docs/security.md); the resident process ended, the next run starts a fresh one",
                 exit_code=1)
        socket_path().unlink(missing_ok=True)
        os._exit(1)


def serve(idle_s: float = IDLE_TIMEOUT_S) -> None:
    from bt_grasp.episode import WarmWorlds  # deferred: the episode stack loads in the resident process only

    if _hold_the_lock() is None:
        log.info("another resident process serves %s; leaving", socket_path())
        return
    path = socket_path()
    path.unlink(missing_ok=True)  # a dead resident's socket: only the lock holder may remove it
    version = code_version()
    key = authkey()
    listener = Listener(str(path), family="AF_UNIX")
    path.chmod(0o600)
    state = {"busy": 0.0, "last": time.monotonic()}
    threading.Thread(target=_watchdog, args=(state, idle_s), daemon=True).start()
    runner = _Runner(WarmWorlds(), version, state)
    import bt_grasp.behaviours  # noqa: F401  # deferred: warms the leaves' imports before the first request

    while True:
        try:
            conn = listener.accept()
        except OSError:
            continue
        handed_over = False
        try:  # a bad client (wrong key, garbage, a huge declared length, silence) loses its connection, no more
            with deadline(conn, CONNECTION_DEADLINE_S):
                server_handshake(conn, key, HANDSHAKE_TIMEOUT_S)
                message = receive(conn, REQUEST_TIMEOUT_S)
            if message["kind"] in ("ping", "stop"):  # answered at once, even while an episode runs
                send(conn, "pong", pid=os.getpid(), code_version=version, busy=bool(state["busy"]))
                if message["kind"] == "stop":
                    conn.close()
                    path.unlink(missing_ok=True)
                    os._exit(0)
            else:
                runner.start(conn, message)
                handed_over = True
        except (WireError, OSError, EOFError) as exc:
            log.warning("dropped a connection: %s", exc)
        except Exception:  # whatever one connection does, the resident goes on serving the others
            log.exception("dropped a connection")
        finally:
            if not handed_over:
                conn.close()
                if not state["busy"]:
                    state["last"] = time.monotonic()


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    serve(float(sys.argv[1]) if len(sys.argv) > 1 else IDLE_TIMEOUT_S)
