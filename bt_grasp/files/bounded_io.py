"""One bounded reader for every file bt_grasp opens that a user gives it or that another file names (trees, scenes,
calibration, fault plans, campaign files, results, meshes and the materials, textures and buffers they name,
URDFs, cache entries, models): a regular file no larger than its kind's limit, read with at most ``limit + 1``
bytes, so ``--faults /dev/zero``, a FIFO or a multi-gigabyte file is one sentence, not an exhausted machine.

``within``: a file another file names must lie inside the folder the naming file allows (a mesh's materials and
textures: the mesh's folder), symbolic links resolved; a name that leaves it is refused before anything is opened.

Within :func:`confined_to` (``replay --resim`` runs a log's own files), every file read here must lie inside one
folder, symbolic links resolved: a tree, scene or calibration taken from a log cannot make bt_grasp read the
user's other files (a scene naming ``/home/me/part.obj`` would carry its shape into the new log)."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from bt_grasp.errors import InputError

_confined: ContextVar[tuple[Path, str] | None] = ContextVar("bt_grasp_confined", default=None)


@contextmanager
def confined_to(root: Path, why: str) -> Iterator[None]:
    """Within the block, :func:`read_user_file` reads only files inside ``root``; ``why`` ends the refusal
    sentence ("a log's inputs may name only the files it carries")."""
    token = _confined.set((Path(os.path.realpath(root)), why))
    try:
        yield
    finally:
        _confined.reset(token)


def _check_confined(path: Path, error: type[InputError]) -> None:
    confined = _confined.get()
    if confined is None:
        return
    root, why = confined
    real = Path(os.path.realpath(path))
    if real != root and root not in real.parents:
        raise error(path, f"lies outside {root}; {why}")

def inside(path: Path, folder: Path) -> bool:
    """Whether ``path``, symbolic links resolved, is ``folder`` or lies below it (``folder``'s links resolved)."""
    real, root = Path(os.path.realpath(path)), Path(os.path.realpath(folder))
    return real == root or root in real.parents


#: text files a user writes by hand: trees, scenes, calibrations, fault plans, campaign files
MAX_TEXT_BYTES = 16 << 20
#: a mesh file, a URDF, a glTF buffer
MAX_MESH_BYTES = 64 << 20
#: a mesh's material file (``.mtl``)
MAX_MATERIAL_BYTES = 4 << 20
#: a picture: a texture image, a dataset picture
MAX_IMAGE_BYTES = 64 << 20
#: a learned detector's ONNX model (a YOLO-OBB export is 6-60 MB)
MAX_MODEL_BYTES = 256 << 20
#: one entry of the collision-shape cache (a few convex parts: kilobytes)
MAX_CACHE_ENTRY_BYTES = 16 << 20
#: a campaign's results (JSON lines: about 1 KB an episode)
MAX_RESULTS_BYTES = 1 << 30


def read_user_file(path: str | Path, limit: int = MAX_TEXT_BYTES, *, error: type[InputError] = InputError,
                   within: Path | None = None, why: str = "") -> bytes:
    """The bytes of ``path``, or ``error(path, one sentence)``: missing, a folder, not a regular file (a device
    such as /dev/zero, a FIFO, a socket), unreadable, or larger than ``limit``; with ``within``, also a path that
    lies outside that folder (``why`` ends the sentence), refused before it is opened."""
    path = Path(path)
    _check_confined(path, error)
    if within is not None and not inside(path, within):
        raise error(path, f"lies outside {within}" + (f"; {why}" if why else ""))
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise error(path, "no such file") from None
    except IsADirectoryError:
        raise error(path, "is a folder, not a file") from None
    except PermissionError:
        raise error(path, "cannot be read: permission denied") from None
    except OSError as exc:
        raise error(path, f"cannot be read: {exc.strerror or exc}") from None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(f.fileno())
        if stat.S_ISDIR(info.st_mode):
            raise error(path, "is a folder, not a file")
        if not stat.S_ISREG(info.st_mode):
            raise error(path, "is not a regular file (a device, pipe or socket); give a file")
        if info.st_size > limit:
            raise error(path, f"is {info.st_size} bytes, over the {limit}-byte limit for this kind of file")
        data = f.read(limit + 1)
    if len(data) > limit:
        raise error(path, f"is over the {limit}-byte limit for this kind of file")
    return data
