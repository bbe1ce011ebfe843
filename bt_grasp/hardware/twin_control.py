"""A client of a twin's own control port (30100; ``bt_grasp.sim.twin.control_port``): the physics judge's verdict for a
run against the twin, its status, and (for tests and benchmarks only) faults and the truth.

One request line out, one JSON line back, bounded (:data:`MAX_REPLY_BYTES`) and within a timeout; a reply that is
not a JSON object with ``ok`` is one sentence (:class:`TwinControlError`).
"""

from __future__ import annotations

import json
import socket
from typing import Any

from bt_grasp.errors import BtGraspError

CONTROL_PORT = 30100
MAX_REPLY_BYTES = 1 << 20


class TwinControlError(BtGraspError):
    """The twin's control port cannot be reached or answered something that is not its protocol."""

    exit_code = 2


def _no_constant(name: str) -> float:
    raise ValueError(name)


def twin_request(host: str, line: str, port: int = CONTROL_PORT, timeout_s: float = 30.0) -> dict[str, Any]:
    """One request on the twin's control port; its JSON reply (``ok`` true or false)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.sendall(line.encode("utf-8") + b"\n")
            buffer = b""
            while not buffer.endswith(b"\n"):
                chunk = sock.recv(65536)
                if not chunk:
                    break
                buffer += chunk
                if len(buffer) > MAX_REPLY_BYTES:
                    raise TwinControlError(f"the twin at {host}:{port} answered more than {MAX_REPLY_BYTES} bytes")
    except OSError as exc:
        raise TwinControlError(f"the twin's control port {host}:{port} cannot be reached ({exc.strerror or exc})") \
            from None
    try:
        reply = json.loads(buffer.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError):
        raise TwinControlError(f"the twin at {host}:{port} answered something that is not JSON") from None
    if not isinstance(reply, dict) or not isinstance(reply.get("ok"), bool):
        raise TwinControlError(f"the twin at {host}:{port} answered a JSON value that is not an object with ok")
    return reply
