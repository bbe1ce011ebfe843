"""Sending one episode to the resident process, starting it first when none is running."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time
from multiprocessing.connection import Client, Connection
from pathlib import Path
from typing import Any

from bt_grasp.episode import EpisodeRequest, EpisodeResult
from bt_grasp.errors import BtGraspError
from bt_grasp.resident.protocol import authkey, code_version, home, request_adapter, result_adapter, socket_path
from bt_grasp.resident.wire import WireError, client_handshake, receive, send

START_TIMEOUT_S = 300.0
HANDSHAKE_TIMEOUT_S = 30.0


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


def _connect() -> Connection | None:
    try:
        conn = Client(str(socket_path()), family="AF_UNIX")
    except (FileNotFoundError, ConnectionRefusedError):
        return None
    try:
        client_handshake(conn, authkey(), HANDSHAKE_TIMEOUT_S)
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
    conn = _connect()
    if conn is None:
        return None, home()
    with conn:
        send(conn, "ping")
        reply = receive(conn, HANDSHAKE_TIMEOUT_S)
    pid = reply.get("pid")
    return (pid if isinstance(pid, int) else None), home()


def stop_resident() -> int | None:
    """Stop this user's resident process if one runs; returns its pid."""
    conn = _connect()
    if conn is None:
        return None
    with conn:
        send(conn, "stop")
        reply = receive(conn, HANDSHAKE_TIMEOUT_S)
    pid = reply.get("pid")
    return pid if isinstance(pid, int) else None
