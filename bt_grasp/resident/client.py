"""Sending one episode to the resident process, starting it first when none is running."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time
from multiprocessing.connection import Client
from pathlib import Path
from typing import Any

from bt_grasp.episode import EpisodeRequest, EpisodeResult
from bt_grasp.errors import BtGraspError
from bt_grasp.resident.protocol import authkey, code_version, home, socket_path

START_TIMEOUT_S = 300.0


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
    return dataclasses.replace(request, **changes)


def _connect() -> Any | None:
    try:
        return Client(str(socket_path()), family="AF_UNIX", authkey=authkey())
    except (FileNotFoundError, ConnectionRefusedError):
        return None


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


def _connect_or_start() -> Any:
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
                conn.send(("run", request, version))
                reply = conn.recv()
        except (EOFError, OSError):
            raise ResidentError(
                f"the resident process ended without answering (killed, or it crashed); see {home() / 'server.log'}"
            ) from None
        if reply[0] == "ok":
            return reply[1], reply[2]
        if reply[0] == "error":
            raise ResidentError(reply[1], reply[2])
        if reply[0] == "stale":  # it ran older code and is exiting: start a current one
            time.sleep(0.5)
            continue
        raise ResidentError(f"the resident process failed: {reply[1].strip().splitlines()[-1]}")
    raise ResidentError("the resident process keeps running other code than this command")


def stop_resident() -> int | None:
    """Stop this user's resident process if one runs; returns its pid."""
    conn = _connect()
    if conn is None:
        return None
    with conn:
        conn.send(("stop",))
        reply = conn.recv()
    return int(reply[1])
