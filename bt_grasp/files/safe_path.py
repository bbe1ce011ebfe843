"""The one gate through which a name read from a file becomes a path on disk.

Logs, results files, campaign files and fault plans carry names (attachment names, scene and fault-plan
names, leaf names) that bt_grasp writes files under. A name from a file is hostile until checked: the rules
are those of CPython's ``tarfile`` "data" filter (PEP 706), applied to names rather than archive members:

- no absolute name (``/etc/passwd``, ``C:\\x``, ``\\\\host\\share``), no drive, no home (``~``);
- no ``..`` component, and no empty or ``.`` component hiding in a multi-part name;
- no NUL or other control character, no backslash (a Windows separator), no name over 255 bytes a part;
- the joined path, with every symbolic link already on disk resolved, stays inside the destination.

:func:`join_under` is for relative paths that may have folders (a tree's ``lib/pick.xml``);
:func:`named_file` is for a file name as mesh formats write them (a material's ``map_Kd``, a glTF ``uri``):
``%20`` escapes, a ``file://`` prefix, ``./`` and backslashes are read as those formats mean them, then the same
rules apply;
:func:`file_component` is for a single file name made from a free-form label (a scene's name in a
campaign), which it maps to a safe slug instead of refusing, so a run keeps going with a readable name.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path, PurePosixPath
from urllib.parse import unquote

from bt_grasp.errors import InputError

MAX_PART_BYTES = 255
MAX_PARTS = 32
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")
_DRIVE = re.compile(r"^[A-Za-z]:")
_SLUG_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def check_relative_name(name: str, *, source: str | Path, what: str = "name") -> PurePosixPath:
    """``name`` as a relative POSIX path of plain parts, or :class:`InputError` saying why it is refused.

    Args:
        name: the name as read from the file (``"tree/lib/pick.xml"``)
        source: the file the name came from, for the error sentence
        what: what the name is, for the error sentence (``"attachment name"``)
    """
    shown = repr(name[:80])
    if not isinstance(name, str) or not name:
        raise InputError(source, f"empty {what}")
    if _CONTROL.search(name):
        raise InputError(source, f"{what} {shown} has a control character")
    if "\\" in name:
        raise InputError(source, f"{what} {shown} has a backslash")
    if name.startswith(("/", "~")) or _DRIVE.match(name):
        raise InputError(source, f"{what} {shown} is absolute; only relative names are accepted")
    parts = name.split("/")
    if len(parts) > MAX_PARTS:
        raise InputError(source, f"{what} {shown} has more than {MAX_PARTS} parts")
    for part in parts:
        if part in ("", ".", ".."):
            raise InputError(source, f"{what} {shown} has a {part or 'empty'!r} part; names may not leave their folder")
        if len(part.encode("utf-8", "surrogateescape")) > MAX_PART_BYTES:
            raise InputError(source, f"{what} {shown} has a part longer than {MAX_PART_BYTES} bytes")
    return PurePosixPath(*parts)


def join_under(root: Path, name: str, *, source: str | Path, what: str = "name") -> Path:
    """``root / name`` after checking ``name`` (:func:`check_relative_name`) and that the result, with the
    symbolic links already on disk resolved, is still inside ``root``. Creates nothing."""
    relative = check_relative_name(name, source=source, what=what)
    base = root.resolve()
    target = (base / relative).resolve()
    if target != base and base not in target.parents:
        raise InputError(source, f"{what} {name[:80]!r} leads outside {root} through a symbolic link")
    return base / relative


def named_file(folder: Path, name: str, *, source: str | Path, what: str = "file name") -> Path:
    """The file a mesh or material file names (``name`` as the format writes it: ``%20`` escapes, a ``file://``
    prefix, ``./`` parts and backslashes allowed), inside ``folder``, or :class:`InputError`: an absolute name, a
    drive (``C:\\textures\\wood.png``), ``..``, a URL or a link out of ``folder`` leaves it. Creates nothing."""
    text = unquote(name.strip().removeprefix("file://")).replace("\\", "/")
    if "://" in text:
        raise InputError(source, f"{what} {name[:80]!r} is a URL; only files beside it are read")
    parts = [part for part in text.split("/") if part != "."] if not text.startswith("/") else [text]
    return join_under(folder, "/".join(parts), source=source, what=what)


def file_component(label: str, *, max_len: int = 80) -> str:
    """One safe file-name component made from a free-form ``label`` (a scene or fault-plan name).

    Letters, digits, ``.``, ``_`` and ``-`` are kept; every other run of characters becomes ``_``; leading
    dots are dropped (no hidden files, no ``..``). When anything was changed or cut, a short hash of the
    original label is appended so that two different labels never share a file name."""
    slug = _SLUG_UNSAFE.sub("_", label).lstrip(".")[:max_len] or "_"
    if slug != label:
        digest = hashlib.sha256(label.encode("utf-8", "surrogateescape")).hexdigest()[:8]
        slug = f"{slug}-{digest}"
    return slug
