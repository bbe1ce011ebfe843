"""The one gate for every file and folder bt_grasp writes where a user says (``--log``, ``--out``, ``--report``,
``--summary-json``, a converted tree, a calibration, a dataset folder, ...).

The attack before issue 22's review found each writer doing its own thing: a dangling symbolic link or a path
under ``/proc`` was a traceback, a FIFO hung the command for ever, ``/dev/full`` failed only after the whole run,
and ``tree convert --force`` over a symbolic link overwrote the file the link pointed at. The rules here:

- **checked before the work** (:func:`check_output_file`, :func:`check_output_folder`): a folder where a file is
  wanted (or the reverse), a device, FIFO or socket, a symbolic link as the last part of the path, or a folder
  where nothing can be created (probed by creating and removing a hidden temporary file) is one sentence, exit 2;
- **written whole, then renamed into place** (:func:`write_output_file`): the bytes go to a temporary file beside
  the target and :func:`os.replace` puts it there, so a link planted at the target is replaced, never followed,
  and a failed write (a full disk) leaves the old file as it was and no half-written one;
- **streams are opened without following a link** (:func:`open_output_stream`) and must be regular files.

A symbolic link earlier in the path (``/tmp`` on some systems, a linked home folder) is the user's own layout and
is followed as usual.
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import BinaryIO

from bt_grasp.errors import InputError


def _problem(exc: OSError) -> str:
    return (exc.strerror or str(exc)).lower()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _probe(folder: Path, flag: str, shown: Path) -> None:
    """Create and remove a hidden file in ``folder``: the honest test that something can be written there."""
    try:
        fd, name = tempfile.mkstemp(dir=folder, prefix=".bt_grasp-probe-")
    except OSError as exc:
        raise InputError(flag, f"cannot write '{shown}': {_problem(exc)} (in '{folder}')") from None
    os.close(fd)
    os.unlink(name)


def _nearest_existing(path: Path) -> Path:
    parent = path.absolute().parent
    while not os.path.lexists(parent) and parent != parent.parent:
        parent = parent.parent
    return parent


def check_output_file(path: str | Path, flag: str, *, example: str = "out.txt",
                      inputs: Sequence[str | Path | None] = ()) -> Path:
    """``path`` if a file can be written there, else :class:`InputError` naming ``flag`` (see the module's
    rules); ``example`` is the file name suggested when ``path`` is a folder; ``inputs``: the files the command
    reads, which it must not write over (`replay run.mcap --report run.mcap` replaced the log with its report).
    Creates nothing."""
    path = Path(path)
    for source in inputs:
        if source is not None and _same_file(path, Path(source)):
            raise InputError(flag, f"'{path}' is the input file {source}; write to another file")
    try:
        info: os.stat_result | None = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):  # the parent is checked below
        info = None
    except OSError as exc:
        raise InputError(flag, f"cannot write '{path}': {_problem(exc)}") from None
    if info is not None:
        if stat.S_ISLNK(info.st_mode):
            raise InputError(flag, f"'{path}' is a symbolic link; bt_grasp does not write through links: give the "
                                   f"file's own path ({os.path.realpath(path)})")
        if stat.S_ISDIR(info.st_mode):
            raise InputError(flag, f"'{path}' is a folder; give a file name such as {path / example}")
        if not stat.S_ISREG(info.st_mode):
            raise InputError(flag, f"'{path}' is not a regular file (a device, pipe or socket); give a file name")
    parent = _nearest_existing(path)
    if not parent.is_dir():
        raise InputError(flag, f"cannot write '{path}': '{parent}' is not a folder")
    _probe(parent, flag, path)
    return path


def _inside(file: Path, folder: Path) -> bool:
    """Whether ``file`` (links resolved) lies in ``folder`` (links resolved), at any depth."""
    real, root = Path(os.path.realpath(file)), Path(os.path.realpath(folder))
    return root in real.parents or real == root


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # either is missing (or unreadable): not the same existing file
        return False


def check_output_folder(path: str | Path, flag: str, *, inputs: Sequence[str | Path | None] = ()) -> Path:
    """``path`` if it is, or can be made, a plain folder to write files into; else :class:`InputError`. ``inputs``:
    the files the command reads, none of which may lie in the folder (a report's figures overwrote results saved
    as ``X_figures/success.png``). Creates nothing (:func:`make_output_folder` does)."""
    path = Path(path)
    for source in inputs:
        if source is not None and _inside(Path(source), path):
            raise InputError(flag, f"the output folder '{path}' holds the input file {source}; write elsewhere")
    try:
        info: os.stat_result | None = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):  # the parent is checked below
        info = None
    except OSError as exc:
        raise InputError(flag, f"cannot write into '{path}': {_problem(exc)}") from None
    if info is not None:
        if stat.S_ISLNK(info.st_mode):
            raise InputError(flag, f"'{path}' is a symbolic link; bt_grasp does not write through links: give the "
                                   f"folder's own path ({os.path.realpath(path)})")
        if not stat.S_ISDIR(info.st_mode):
            raise InputError(flag, f"'{path}' is a file, not a folder")
        _probe(path, flag, path)
        return path
    parent = _nearest_existing(path)
    if not parent.is_dir():
        raise InputError(flag, f"cannot make the folder '{path}': '{parent}' is not a folder")
    _probe(parent, flag, path)
    return path


def make_output_folder(path: str | Path, flag: str, *, inputs: Sequence[str | Path | None] = ()) -> Path:
    """:func:`check_output_folder`, then the folder made (with its parents)."""
    path = check_output_folder(path, flag, inputs=inputs)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(flag, f"cannot make the folder '{path}': {_problem(exc)}") from None
    return path


def write_output_file(path: str | Path, data: bytes | str, flag: str, *, example: str = "out.txt") -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` whole: checked (:func:`check_output_file`), written to a
    temporary file beside it, then renamed over it. Any failure is :class:`InputError` and leaves ``path`` as it
    was."""
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    return _replace(path, lambda f: f.write(payload), flag, example)


def copy_output_file(source: str | Path, path: str | Path, flag: str, *, example: str = "out.txt") -> Path:
    """:func:`write_output_file` with the bytes of the file ``source`` (streamed, not read whole)."""
    def copy(f: BinaryIO) -> None:
        with open(source, "rb") as src:
            shutil.copyfileobj(src, f, 1 << 20)

    return _replace(path, copy, flag, example)


def _replace(path: str | Path, fill: Callable[[BinaryIO], object], flag: str, example: str) -> Path:
    path = check_output_file(path, flag, example=example)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name[:80]}.", suffix=".part")
    except OSError as exc:
        raise InputError(flag, f"cannot write '{path}': {_problem(exc)}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            os.fchmod(f.fileno(), 0o666 & ~_umask())
            fill(f)
        os.replace(name, path)
    except OSError as exc:
        Path(name).unlink(missing_ok=True)
        raise InputError(flag, f"cannot write '{path}': {_problem(exc)}") from None
    return path


def open_output_stream(path: str | Path, flag: str, *, append: bool = False) -> int:
    """A descriptor open for writing (appending with ``append``, else truncated) on a regular file at ``path``,
    created if missing; never through a symbolic link, never on a device or FIFO (opened without blocking)."""
    path = check_output_file(path, flag)
    mode = os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
    mode |= os.O_APPEND if append else os.O_TRUNC
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, mode, 0o666)
    except OSError as exc:
        raise InputError(flag, f"cannot write '{path}': {_problem(exc)}") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise InputError(flag, f"'{path}' is not a regular file (a device, pipe or socket); give a file name")
    os.set_blocking(fd, True)
    return fd
