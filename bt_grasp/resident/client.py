"""Sending one episode to the resident process, starting it first when none is running."""

from __future__ import annotations

import dataclasses
import fcntl
import os
import signal
import subprocess
import sys
import time
from multiprocessing.connection import Client, Connection
from pathlib import Path
from typing import Any

from bt_grasp.episode import EpisodeRequest, EpisodeResult
from bt_grasp.errors import BtGraspError, InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.resident.protocol import (
    authkey,
    code_version,
    home,
    lock_path,
    request_adapter,
    result_adapter,
    socket_path,
)
from bt_grasp.resident.wire import WireError, client_handshake, receive, send

START_TIMEOUT_S = 300.0
HANDSHAKE_TIMEOUT_S = 30.0
#: ``status`` and ``stop`` wait this long for an answer (the resident answers them at once, even while an
#: episode runs); past it, ``stop`` ends the process by its recorded pid
QUICK_TIMEOUT_S = 5.0
#: after SIGTERM, how long ``stop`` waits before SIGKILL
TERM_WAIT_S = 5.0


class ResidentError(BtGraspError):
    """What the resident process answered instead of a result (bad input keeps its exit code 2)."""

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code


def _absolute(request: EpisodeRequest) -> EpisodeRequest:
    """The resident process has its own working folder: every path goes as an absolute one."""
    changes: dict[str, Any] = {}
    for field in ("tree", "scene", "calibration", "log", "faults"):
        value = getattr(request, field)
        if value is not None:
            changes[field] = Path(value).absolute()
    # --leaves plugin files too (a module name stays a module name)
    changes["leaves"] = tuple(str(Path(v).absolute()) if v.endswith(".py") else v for v in request.leaves)
    return dataclasses.replace(request, **changes)


def _connect(timeout_s: float = HANDSHAKE_TIMEOUT_S) -> Connection | None:
    try:
        conn = Client(str(socket_path()), family="AF_UNIX")
    except (FileNotFoundError, ConnectionRefusedError):
        return None
    try:
        client_handshake(conn, authkey(), timeout_s)
    except (WireError, OSError) as exc:
        conn.close()
        raise ResidentError(f"the process on {socket_path()} failed the resident's handshake: {exc}") from None
    return conn


def _start() -> None:
    log = (home() / "server.log").open("ab")
    with log:
        subprocess.Popen(
            [sys.executable, "-m", "bt_grasp.resident.server"],
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=log,
            start_new_session=True,
            cwd="/",
        )


def _connect_or_start() -> Connection:
    conn = _connect()
    if conn is not None:
        return conn
    _start()  # it removes a dead resident's socket itself, under its lock; a second one started meanwhile leaves
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        time.sleep(0.1)
        conn = _connect()
        if conn is not None:
            return conn
    raise ResidentError(
        f"the resident process did not start within {START_TIMEOUT_S:.0f} s; see {home() / 'server.log'}"
    )


def run_resident(request: EpisodeRequest) -> tuple[EpisodeResult, int]:
    """Run ``request`` in the resident process (started if needed); returns the result and that process's pid."""
    request = _absolute(request)
    version = code_version()
    for _attempt in range(2):
        conn = _connect_or_start()
        try:
            with conn:
                send(conn, "run", request=request_adapter().dump_python(request, mode="json"), code_version=version)
                reply = receive(conn, None)
        except (WireError, OSError) as exc:
            raise ResidentError(
                f"the resident process ended without answering (killed, or it crashed: {exc}); "
                f"see {home() / 'server.log'}"
            ) from None
        kind = reply["kind"]
        if kind == "ok":
            try:
                return result_adapter().validate_python(reply.get("result")), int(reply["pid"])
            except (ValueError, KeyError, TypeError) as exc:
                raise ResidentError(f"the resident process answered a malformed result: {exc}") from None
        if kind == "error":
            code = reply.get("exit_code")
            raise ResidentError(str(reply.get("message"))[:2000], code if code in (1, 2) else 1)
        if kind == "stale":  # it ran older code and is exiting: start a current one
            time.sleep(0.5)
            continue
        lines = str(reply.get("message", "")).strip().splitlines() or ["no detail"]
        raise ResidentError(f"the resident process failed: {lines[-1][:500]}")
    raise ResidentError("the resident process keeps running other code than this command")


def resident_status() -> tuple[int | None, Path]:
    """The pid of the resident process serving this user's folder (None: none runs), and the folder."""
    conn = _connect(QUICK_TIMEOUT_S)
    if conn is None:
        return None, home()
    with conn:
        send(conn, "ping")
        reply = receive(conn, QUICK_TIMEOUT_S)
    pid = reply.get("pid")
    return (pid if isinstance(pid, int) else None), home()


def stop_resident() -> int | None:
    """Stop this user's resident process if one runs; returns its pid. It is asked first; when it does not
    answer within :data:`QUICK_TIMEOUT_S` (wedged, stopped, or not a resident at all), the process that holds the
    folder's lock is ended by the pid it recorded there, if it is this user's resident (SIGTERM, then SIGKILL)."""
    try:
        conn = _connect(QUICK_TIMEOUT_S)
    except ResidentError:
        conn = None
    else:
        if conn is None:
            return _signal_recorded() if _lock_is_held() else None
        try:
            with conn:
                send(conn, "stop")
                reply = receive(conn, QUICK_TIMEOUT_S)
            pid = reply.get("pid")
            if isinstance(pid, int):
                _wait_gone(pid, TERM_WAIT_S)
                return pid
        except (WireError, OSError, EOFError):
            pass
    return _signal_recorded()


def _lock_is_held() -> bool:
    """Whether a process holds the folder's resident lock (only a living resident does)."""
    try:
        fd = os.open(lock_path(), os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def _signal_recorded() -> int | None:
    """End the resident by the pid in its lock file: only while that lock is held (the pid is then the holder's,
    not a reused number) and only a process of this user running ``bt_grasp.resident.server``."""
    if not _lock_is_held():
        return None
    try:
        pid = int(read_user_file(lock_path(), 64).decode().strip())
        info = os.stat(f"/proc/{pid}")
        command = read_user_file(Path(f"/proc/{pid}/cmdline"), 1 << 16)
    except (InputError, ValueError, OSError):
        raise ResidentError(f"the resident process does not answer and its pid cannot be read from {lock_path()}"
                            ) from None
    if info.st_uid != os.getuid() or b"bt_grasp.resident.server" not in command:
        raise ResidentError(f"the process {pid} that holds {lock_path()} is not this user's resident; it is left "
                            "alone")
    os.kill(pid, signal.SIGCONT)  # a stopped process cannot act on SIGTERM
    os.kill(pid, signal.SIGTERM)
    if not _wait_gone(pid, TERM_WAIT_S):
        os.kill(pid, signal.SIGKILL)
        _wait_gone(pid, TERM_WAIT_S)
    socket_path().unlink(missing_ok=True)
    return pid


def _wait_gone(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        if Path(f"/proc/{pid}/stat").exists():
            try:
                if read_user_file(Path(f"/proc/{pid}/stat"), 4096).split(b")")[-1].split()[0] == b"Z":
                    return True  # a zombie: it has ended, its parent has not reaped it yet
            except (InputError, IndexError):
                return True
        time.sleep(0.05)
    return False
