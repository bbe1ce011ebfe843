"""Where a file a user's file names by a relative path is looked for: beside it, on a search path, then in bt_grasp.

A tree's ``<include path="lib/pick.xml"/>`` and a scene's ``calibration: tabletop.calibration.yaml`` are looked
for in the same three places, in this order, and the first file found is used:

1. the folder of the file that names it (a tree's includes, a scene's calibration: as BT.CPP resolves includes);
2. each folder of an environment variable (``BT_GRASP_TREE_PATH``, ``BT_GRASP_CALIBRATION_PATH``), folders
   separated by ``os.pathsep`` (``:`` on Linux), in order;
3. what bt_grasp ships in its package (``bt_grasp/assets/trees``: the library subtrees ``lib/pick.xml`` and
   ``lib/place.xml``; ``bt_grasp/assets/calibrations``: the shipped scenes' calibration files).

An absolute name is the user's own choice and is looked for there only. When nothing is found, the error
names every place looked (:func:`looked_in`). Names written by the user in their own files are the user's
(a tree may include ``/home/me/lib/x.xml``); names read from a log never come here (``replay --resim`` reads a
log's own attachments only: ``bt_grasp/cli/resim.py``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

#: the folder of bt_grasp's shipped data files (package data: pyproject.toml)
ASSETS = Path(__file__).resolve().parents[1] / "assets"
#: the shipped tree library's root: ``lib/pick.xml`` is ``SHIPPED_TREES / "lib/pick.xml"``
SHIPPED_TREES = ASSETS / "trees"
#: the shipped scenes' calibration files
SHIPPED_CALIBRATIONS = ASSETS / "calibrations"
#: environment variables of folders searched after the naming file's own folder
TREE_PATH_VARIABLE = "BT_GRASP_TREE_PATH"
CALIBRATION_PATH_VARIABLE = "BT_GRASP_CALIBRATION_PATH"


@dataclass(frozen=True)
class Found:
    """The outcome of a search: the file (None when nothing was found) and every place looked, in order, each
    with where it came from (``beside``, ``search path``, ``shipped``, ``absolute``)."""

    path: Path | None
    looked: tuple[tuple[str, str], ...]


def search_folders(variable: str, environ: Mapping[str, str] | None = None) -> list[Path]:
    """The folders an environment variable lists (``os.pathsep``-separated; empty entries left out)."""
    value = (os.environ if environ is None else environ).get(variable, "")
    return [Path(part) for part in value.split(os.pathsep) if part.strip()]


def find_named_file(name: str, beside: Path, variable: str, shipped: Path,
                    environ: Mapping[str, str] | None = None) -> Found:
    """The first regular file ``name`` names: ``beside / name``, then each folder of ``$variable``, then
    ``shipped / name``; an absolute ``name`` is looked for as it is only.

    Args:
        name: the path as the user's file writes it (``lib/pick.xml``)
        beside: the folder of the file that names it (a path as displayed, relative or absolute)
        variable: the search path's environment variable (:data:`TREE_PATH_VARIABLE`)
        shipped: bt_grasp's own folder, searched last
        environ: the environment (``os.environ`` when None)
    """
    if os.path.isabs(name):
        candidates = [("absolute", Path(name))]
    else:
        folders = [("beside", beside), *(("search path", f) for f in search_folders(variable, environ)),
                   ("shipped", shipped)]
        candidates = [(kind, Path(os.path.normpath(os.path.join(folder, name)))) for kind, folder in folders]
    looked: list[tuple[str, str]] = []
    for kind, candidate in candidates:
        looked.append((kind, str(candidate)))
        if candidate.is_file():
            return Found(candidate, tuple(looked))
    return Found(None, tuple(looked))


def looked_in(found: Found, variable: str) -> str:
    """Every place a failed search looked, as the end of one sentence: "looked beside it (a), in
    $BT_GRASP_TREE_PATH (not set) and in bt_grasp's shipped files (c)"."""
    if [kind for kind, _ in found.looked] == ["absolute"]:
        return f"looked at {found.looked[0][1]}"
    by_kind: dict[str, list[str]] = {}
    for kind, place in found.looked:
        by_kind.setdefault(kind, []).append(place)
    searched = ", ".join(by_kind.get("search path", [])) or "not set"
    return (f"looked beside it ({', '.join(by_kind.get('beside', []))}), in ${variable} ({searched}) and in "
            f"bt_grasp's shipped files ({', '.join(by_kind.get('shipped', []))})")
