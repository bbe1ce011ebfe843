"""The resident episode process: accepts one episode request at a time on a Unix socket, runs it warm."""

from __future__ import annotations

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


def _watchdog(state: dict[str, float], idle_s: float) -> None:
    while True:
        time.sleep(min(5.0, idle_s))
        if not state["busy"] and time.monotonic() - state["last"] > idle_s:
            socket_path().unlink(missing_ok=True)
            os._exit(0)


def _handle(message: dict[str, Any], worlds: Any, version: str) -> tuple[str, dict[str, Any]]:
    """The reply (kind, fields) to one message; a request that does not validate is an ``error`` reply."""
    kind = message["kind"]
    if kind in ("ping", "stop"):
        return "pong", {"pid": os.getpid(), "code_version": version}
    if kind != "run":
        return "error", {"message": f"unknown request {kind[:40]!r}", "exit_code": 2}
    if message.get("code_version") != version:
        return "stale", {"code_version": version}
    from pydantic import ValidationError

    from bt_grasp.episode import EpisodeRequest, run_episode

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


def serve(idle_s: float = IDLE_TIMEOUT_S) -> None:
    from bt_grasp.episode import WarmWorlds

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
    worlds = WarmWorlds()
    import bt_grasp.behaviours  # noqa: F401  (warm the imports before the first request)

    while True:
        try:
            conn = listener.accept()
        except OSError:
            continue
        state["busy"] = 1.0
        stop = False
        try:  # a bad client (wrong key, garbage, a huge declared length, silence) loses its connection, no more
            with deadline(conn, CONNECTION_DEADLINE_S):
                server_handshake(conn, key, HANDSHAKE_TIMEOUT_S)
                message = receive(conn, REQUEST_TIMEOUT_S)
            kind, fields = _handle(message, worlds, version)
            send(conn, kind, **fields)
            stop = kind == "stale" or message["kind"] == "stop"  # the code changed under it, or asked to stop
        except (WireError, OSError, EOFError) as exc:
            log.warning("dropped a connection: %s", exc)
        except Exception:  # whatever one connection does, the resident goes on serving the others
            log.exception("dropped a connection")
        finally:
            conn.close()
            state["busy"] = 0.0
            state["last"] = time.monotonic()
        if stop:
            path.unlink(missing_ok=True)
            os._exit(0)

if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    serve(float(sys.argv[1]) if len(sys.argv) > 1 else IDLE_TIMEOUT_S)
