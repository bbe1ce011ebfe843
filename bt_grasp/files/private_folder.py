"""A folder only this user controls: the one check for every folder whose contents bt_grasp trusts without reading
them as hostile (the resident's socket and key, the collision-shape cache).

Ownership is the defence: whoever can write an entry can write its hash too, so a cache's content hash proves
nothing about who wrote it. A folder is trusted only when it is a plain folder (not a symbolic link) owned by this
user that neither the group nor others can write, and when no folder on the way to it lets someone else swap it
for their own: one owned by another user than root or this one, or writable by others without the sticky bit
(``/tmp`` has it: there others cannot rename what is not theirs), as OpenSSH's StrictModes checks. Such a folder
is refused (exit 2, one sentence), never "repaired"; a folder of this user's that is merely readable by others is
made 0700.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from bt_grasp.errors import InputError


def unsafe_ancestor(path: Path) -> tuple[Path, str] | None:
    """A folder on the way to ``path`` that someone else could use to swap the folder for their own, and why.
    Both the path as given (the folders holding each of its names, a symbolic link's included) and its real path
    are checked."""
    given = path.absolute()
    folders = {Path(os.path.realpath(p.parent)) for p in (given, *given.parents) if p != p.parent}
    folders |= set(Path(os.path.realpath(given)).parents)
    for folder in sorted(folders):
        info = os.stat(folder)
        if info.st_uid not in (0, os.getuid()):
            return folder, f"belongs to user id {info.st_uid}"
        if info.st_mode & 0o022 and not info.st_mode & stat.S_ISVTX:
            return folder, f"is writable by others without the sticky bit (mode {stat.S_IMODE(info.st_mode):o})"
    return None


def check_private(path: Path, source: str, what: str) -> None:
    """:class:`InputError` (naming ``source``) unless ``path`` is a folder only this user controls (see the
    module's rules); ``what`` names its use in the sentence ("the resident", "the mesh cache")."""
    unsafe = unsafe_ancestor(path)
    if unsafe is not None:
        raise InputError(source, f"{path} lies in {unsafe[0]}, which {unsafe[1]}: someone else could swap the folder "
                         f"for their own; {what} refuses it")
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        raise InputError(source, f"{path} is not a plain folder (a symbolic link or a file); {what} refuses it")
    if info.st_uid != os.getuid():
        raise InputError(source, f"{path} belongs to user id {info.st_uid}, not to you; {what} refuses a "
                         "folder another user controls")
    if info.st_mode & 0o022:
        raise InputError(source, f"{path} is writable by others (mode {stat.S_IMODE(info.st_mode):o}); {what} "
                         "refuses a shared folder: point it at a private one")
    if stat.S_IMODE(info.st_mode) != 0o700:
        path.chmod(0o700)


def private_folder(path: Path, source: str, what: str) -> Path:
    """``path`` made if missing (0700, with its parents) and checked (:func:`check_private`)."""
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
    except FileExistsError:  # a file, or a dangling link, where the folder should be
        pass
    except OSError as exc:
        raise InputError(source, f"{path} cannot be made ({(exc.strerror or str(exc)).lower()}); {what} needs a "
                         "folder of yours") from None
    check_private(path, source, what)
    return path
