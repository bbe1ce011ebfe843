"""The resident's wire format: a mutual HMAC handshake, then length-bounded, versioned JSON messages.

Nothing read from the socket is unpickled. Each message is one ``send_bytes`` frame of at most
:data:`MAX_MESSAGE_BYTES` (a longer declared length is refused before anything is allocated), holding a JSON
object with ``"v"`` (:data:`VERSION`) and ``"kind"``; episode requests and results travel as their typed
dataclasses dumped and validated by pydantic, so a malformed field is a refusal, not a crash. Every read
waits at most a given time, so a silent peer cannot hold the other end.

The handshake proves both ends know this user's key (``protocol.authkey``): the server sends a challenge,
the client answers with ``HMAC(key, "client" + challenge)`` and a challenge of its own, which the server
answers with ``HMAC(key, "server" + challenge)``.
"""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import json
import os
import secrets
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from multiprocessing.connection import Connection
from typing import Any

from bt_grasp.errors import BtGraspError

VERSION = 1
MAX_MESSAGE_BYTES = 1 << 20
MAGIC = b"BTGR1"
_NONCE = 32


class WireError(BtGraspError):
    """The peer broke the protocol (bad key, bad frame, too long, too slow, wrong version)."""


@contextmanager
def deadline(conn: Connection, seconds: float) -> Iterator[None]:
    """Within the block, ``conn`` is shut down once ``seconds`` have passed: a peer that sends part of a frame
    and then goes silent, or trickles a byte at a time, cannot hold the other end longer than that (``poll``
    only waits for the first byte; ``recv_bytes`` then blocks until the whole frame is there)."""
    sock = socket.socket(fileno=os.dup(conn.fileno()))

    def cut() -> None:
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_RDWR)

    timer = threading.Timer(seconds, cut)
    timer.daemon = True
    timer.start()
    try:
        yield
    except (EOFError, OSError, WireError):
        if not timer.is_alive():
            raise WireError(f"the peer took more than {seconds:g} s") from None
        raise
    finally:
        timer.cancel()
        sock.close()


def _recv_frame(conn: Connection, timeout_s: float | None, limit: int = MAX_MESSAGE_BYTES) -> bytes:
    if timeout_s is not None and not conn.poll(timeout_s):
        raise WireError(f"no message within {timeout_s:g} s")
    try:
        return conn.recv_bytes(limit)
    except OSError as exc:  # includes "bad message length" for a frame over the limit
        raise WireError(f"unreadable frame ({exc})") from None
    except EOFError:
        raise WireError("the peer closed the connection") from None


def _mac(key: bytes, who: bytes, challenge: bytes) -> bytes:
    return hmac.new(key, who + challenge, hashlib.sha256).digest()


def server_handshake(conn: Connection, key: bytes, timeout_s: float) -> None:
    challenge = secrets.token_bytes(_NONCE)
    conn.send_bytes(MAGIC + challenge)
    answer = _recv_frame(conn, timeout_s, limit=256)
    if len(answer) != 32 + _NONCE or not hmac.compare_digest(answer[:32], _mac(key, b"client", challenge)):
        raise WireError("the client does not know this user's key")
    conn.send_bytes(_mac(key, b"server", answer[32:]))


def client_handshake(conn: Connection, key: bytes, timeout_s: float) -> None:
    hello = _recv_frame(conn, timeout_s, limit=256)
    if len(hello) != len(MAGIC) + _NONCE or not hello.startswith(MAGIC):
        raise WireError("the process on the socket does not speak the resident's protocol")
    mine = secrets.token_bytes(_NONCE)
    conn.send_bytes(_mac(key, b"client", hello[len(MAGIC):]) + mine)
    proof = _recv_frame(conn, timeout_s, limit=256)
    if not hmac.compare_digest(proof, _mac(key, b"server", mine)):
        raise WireError("the process on the socket does not know this user's key")


def send(conn: Connection, kind: str, **fields: Any) -> None:
    data = json.dumps({"v": VERSION, "kind": kind, **fields}, separators=(",", ":")).encode()
    if len(data) > MAX_MESSAGE_BYTES:
        raise WireError(f"a {kind!r} message of {len(data)} bytes is over the {MAX_MESSAGE_BYTES}-byte limit")
    conn.send_bytes(data)


def receive(conn: Connection, timeout_s: float | None) -> dict[str, Any]:
    """The next message as a dict with ``v == VERSION`` and a string ``kind``, or :class:`WireError`."""
    raw = _recv_frame(conn, timeout_s)
    try:
        message = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise WireError(f"not JSON ({exc})") from None
    except (RecursionError, ValueError) as exc:  # nested too deeply; an integer of more digits than Python reads
        raise WireError(f"not a message ({type(exc).__name__})") from None
    if not isinstance(message, dict) or not isinstance(message.get("kind"), str):
        raise WireError("a message must be a JSON object with a 'kind'")
    if message.get("v") != VERSION:
        raise WireError(f"protocol version {message.get('v')!r}; this bt_grasp speaks {VERSION}")
    return message
