"""The resident episode process: accepts one episode request at a time on a Unix socket, runs it warm."""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
import traceback
from multiprocessing.connection import Listener
from typing import Any

from bt_grasp.errors import BtGraspError
from bt_grasp.resident.protocol import IDLE_TIMEOUT_S, authkey, code_version, socket_path

log = logging.getLogger(__name__)


def _watchdog(state: dict[str, float], idle_s: float) -> None:
    while True:
        time.sleep(min(5.0, idle_s))
        if not state["busy"] and time.monotonic() - state["last"] > idle_s:
            socket_path().unlink(missing_ok=True)
            os._exit(0)


def _handle(message: Any, worlds: Any, version: str) -> tuple[Any, ...]:
    kind = message[0]
    if kind in ("ping", "stop"):
        return ("pong", os.getpid(), version)
    if kind != "run":
        return ("crash", f"unknown request {kind!r}")
    _, request, client_version = message
    if client_version != version:
        return ("stale", version)
    from bt_grasp.episode import run_episode

    try:
        return ("ok", run_episode(request, worlds=worlds), os.getpid())
    except BtGraspError as exc:
        return ("error", str(exc), exc.exit_code)
    except Exception:
        return ("crash", traceback.format_exc())


def serve(idle_s: float = IDLE_TIMEOUT_S) -> None:
    from bt_grasp.episode import WarmWorlds

    path = socket_path()
    path.unlink(missing_ok=True)
    version = code_version()
    listener = Listener(str(path), family="AF_UNIX", authkey=authkey())
    path.chmod(0o600)
    state = {"busy": 0.0, "last": time.monotonic()}
    threading.Thread(target=_watchdog, args=(state, idle_s), daemon=True).start()
    worlds = WarmWorlds()
    import bt_grasp.behaviours  # noqa: F401  (warm the imports before the first request)

    while True:
        try:
            conn = listener.accept()
        except (OSError, EOFError):  # a client that failed the handshake
            continue
        state["busy"] = 1.0
        try:
            message = conn.recv()
            reply = _handle(message, worlds, version)
            conn.send(reply)
            if reply[0] == "stale" or message[0] == "stop":  # the code changed under it, or asked to stop
                path.unlink(missing_ok=True)
                os._exit(0)
        except (OSError, EOFError):
            pass
        finally:
            conn.close()
            state["busy"] = 0.0
            state["last"] = time.monotonic()


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    serve(float(sys.argv[1]) if len(sys.argv) > 1 else IDLE_TIMEOUT_S)
