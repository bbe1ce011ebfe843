"""Where the resident process listens and how a client proves it is the same user and the same code."""

from __future__ import annotations

import hashlib
import os
import secrets
from pathlib import Path

import bt_grasp

#: the resident process exits after this long without a request
IDLE_TIMEOUT_S = 600.0


def home() -> Path:
    """A folder only this user can read: the socket, its key and the process's log live there."""
    base = os.environ.get("BT_GRASP_RESIDENT_DIR") or str(Path.home() / ".cache" / "bt_grasp" / "resident")
    path = Path(base)
    path.mkdir(parents=True, exist_ok=True)
    path.chmod(0o700)
    return path


def socket_path() -> Path:
    return home() / "episode.sock"


def authkey() -> bytes:
    """The shared secret of this user's client and resident process (created once, mode 0600)."""
    path = home() / "key"
    if not path.exists():
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(secrets.token_bytes(32))
    return path.read_bytes()


def code_version() -> str:
    """Changes whenever a source file of bt_grasp changes: a resident process never runs stale code."""
    root = Path(bt_grasp.__file__).parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        stat = path.stat()
        h.update(f"{path.relative_to(root)}:{stat.st_size}:{stat.st_mtime_ns}".encode())
    return h.hexdigest()[:16]
