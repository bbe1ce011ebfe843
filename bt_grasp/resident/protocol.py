"""Where the resident process listens and how a client proves it is the same user and the same code."""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.errors import InputError
from bt_grasp.files.private_folder import check_private
from bt_grasp.process.code_fingerprint import code_fingerprint

if TYPE_CHECKING:
    from pydantic import TypeAdapter

    from bt_grasp.episode import EpisodeRequest, EpisodeResult

#: the resident process exits after this long without a request
IDLE_TIMEOUT_S = 600.0


ENV_DIR = "BT_GRASP_RESIDENT_DIR"
#: the shared key's length (HMAC-SHA256: 32 bytes is its full strength)
KEY_BYTES = 32


def home() -> Path:
    """A folder only this user can read: the socket, its key and the process's log live there.

    A folder someone else could have prepared is refused (exit 2), never repaired
    (:mod:`bt_grasp.files.private_folder`): one owned by another user (they could have put their own key and
    socket there, and the client would talk to their process), one that is a symbolic link, or one writable by
    the group or others. A folder of this user's that is merely readable by others is made private (0700)."""
    base = os.environ.get(ENV_DIR) or str(Path.home() / ".cache" / "bt_grasp" / "resident")
    path = Path(base)
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_private(path, ENV_DIR if os.environ.get(ENV_DIR) else "the resident folder", "the resident")
    return path


def lock_path() -> Path:
    """Held (``flock``) by the one resident process of this folder for as long as it lives."""
    return home() / "resident.lock"


def socket_path() -> Path:
    return home() / "episode.sock"


def authkey() -> bytes:
    """The shared secret of this user's client and resident process (created once, mode 0600, whole: it is
    written under another name and linked into place, so a crash never leaves a short key)."""
    path = home() / "key"
    if not os.path.lexists(path):
        part = path.with_name(f"key.{secrets.token_hex(8)}.part")
        fd = os.open(part, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(secrets.token_bytes(KEY_BYTES))
                f.flush()
                os.fsync(f.fileno())
            with contextlib.suppress(FileExistsError):  # a racing client made one first: both use that one
                os.link(part, path)
        finally:
            part.unlink(missing_ok=True)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError as exc:  # a symbolic link (ELOOP), or unreadable
        raise InputError(path, f"the resident's key cannot be opened ({(exc.strerror or str(exc)).lower()}); "
                         "remove it to make a new one") from None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(f.fileno())
        if info.st_uid != os.getuid() or info.st_mode & 0o077 or not stat.S_ISREG(info.st_mode):
            raise InputError(path, "the resident's key must be a private (0600) file of yours; remove it to make a "
                             "new one")
        key = f.read(64)
    if len(key) < KEY_BYTES:  # an empty or cut key (a crash while it was made) would make the proof worthless
        raise InputError(path, f"the resident's key holds {len(key)} bytes, not {KEY_BYTES}; remove it to make a "
                         "new one")
    return key


def code_version() -> str:
    """Changes whenever the content of any bt_grasp file (sources, shaders, assets) or the version of a library
    that simulates, renders, perceives or plans changes: a resident process never runs stale code
    (``bt_grasp.process.code_fingerprint``)."""
    return code_fingerprint()


@cache
def request_adapter() -> TypeAdapter[EpisodeRequest]:
    """Episode requests on the wire: typed JSON, validated field by field (no pickle)."""
    from pydantic import TypeAdapter

    from bt_grasp.episode import EpisodeRequest  # deferred: the episode stack loads on decoding, not on import

    return TypeAdapter(EpisodeRequest)


@cache
def result_adapter() -> TypeAdapter[EpisodeResult]:
    from pydantic import TypeAdapter

    from bt_grasp.episode import EpisodeResult  # deferred: as above

    return TypeAdapter(EpisodeResult)
