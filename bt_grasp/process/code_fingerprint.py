"""The code fingerprint: one short digest of the code and libraries a process runs, defined once.

It changes when anything that changes a run changes:

- the content of any file of the bt_grasp package: Python sources, shaders, URDFs, assets, JSON and YAML data
  (all files, except the interpreter's ``__pycache__``, which is derived from the sources);
- the installed version of a library that simulates, renders, perceives or plans (:data:`DEPENDENCIES`, read
  from package metadata: nothing is imported).

A modification time alone does not change it (a ``touch``, a checkout that writes the same bytes again). Within
one process each file's content digest is kept, keyed by its path, size, inode and change times, so a second
call only stats the files. Measured on the 2-core machine (220 files, 1.7 MB): about 16 ms the first time in a
process (8 ms to read and hash the files, 8 ms to read the versions' metadata), about 4 ms after.

The resident process compares it to decide whether its warm code is stale (``bt_grasp.resident.protocol``);
every campaign results row carries it in its environment (``bt_grasp.campaign.environment``).
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from pathlib import Path

import bt_grasp
from bt_grasp.process.environment import library_version

#: the distributions whose versions change a run: simulation and rendering, perception, planning and
#: collision, trajectories, numerics, the tree library and the log format
DEPENDENCIES = (
    "sapien", "py-trees", "numpy", "scipy", "open3d", "opencv-python", "opencv-python-headless",
    "pin", "libpinocchio", "coal", "libcoal", "ompl", "ruckig", "mcap",
)

#: folders and suffixes that are not the package's content (the interpreter derives them from the sources)
_SKIPPED_DIRS = frozenset({"__pycache__"})
_SKIPPED_SUFFIXES = (".pyc", ".pyo")

_Key = tuple[str, int, int, int, int]
_file_digests: dict[_Key, str] = {}


def package_root() -> Path:
    return Path(bt_grasp.__file__).resolve().parent


def _files(root: Path) -> list[Path]:
    found: list[Path] = []
    for folder, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in _SKIPPED_DIRS)
        found.extend(Path(folder) / n for n in names if not n.endswith(_SKIPPED_SUFFIXES))
    return sorted(found, key=lambda p: p.relative_to(root).as_posix())


def _file_digest(path: Path) -> str | None:
    """The sha256 of a regular file's content (cached while its size, inode and times stay), or None if it is
    not a regular file or vanished while we looked (an editor's temporary file)."""
    try:
        info = path.stat()
    except OSError:
        return None
    if not stat.S_ISREG(info.st_mode):
        return None
    key = (str(path), info.st_size, info.st_ino, info.st_mtime_ns, info.st_ctime_ns)
    digest = _file_digests.get(key)
    if digest is None:
        h = hashlib.sha256()
        try:
            with open(path, "rb") as f:
                while chunk := f.read(1 << 20):
                    h.update(chunk)
        except FileNotFoundError:
            return None
        except OSError as exc:  # unreadable: its name and the reason still go in (a change of either counts)
            return f"unreadable: {exc.strerror}"
        digest = _file_digests[key] = h.hexdigest()
    return digest


def package_digest(root: Path | None = None) -> str:
    """The digest of every file's relative path and content under ``root`` (the bt_grasp package)."""
    root = root or package_root()
    h = hashlib.sha256()
    for path in _files(root):
        digest = _file_digest(path)
        if digest is not None:
            h.update(f"{path.relative_to(root).as_posix()}\0{digest}\n".encode())
    return h.hexdigest()


def dependency_versions() -> dict[str, str]:
    """The installed version of each of :data:`DEPENDENCIES` ("?" for one not installed)."""
    return {name: library_version(name) for name in DEPENDENCIES}


def code_fingerprint(root: Path | None = None) -> str:
    """16 hex digits: the package's content and the dependencies' versions (see the module's text)."""
    payload = {"package": package_digest(root), "dependencies": dependency_versions()}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]
