"""A URDF's mesh file names made paths: relative to the URDF, absolute, ``file://``, or ``package://NAME/PATH``.

NAME is found in the scene's ``packages:`` map, else as a folder above the URDF named NAME or holding a
``package.xml`` that names NAME, else as a folder NAME beside one of those folders (a workspace's ``src/``),
looking at most :data:`PACKAGE_SEARCH_DEPTH` folders up. PATH goes through the one gate for names read from
files (:func:`bt_grasp.files.safe_path.check_relative_name`): no ``..``, nothing absolute. Other URLs are refused.
Only read here: a ``package.xml`` (bounded) and whether folders exist.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping
from pathlib import Path

from bt_grasp.errors import ConfigError, InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.safe_path import check_relative_name

log = logging.getLogger(__name__)

#: how many folders above the URDF a ``package://`` name is looked for
PACKAGE_SEARCH_DEPTH = 6
_PACKAGE_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


class MeshResolver:
    """Mesh file names of one URDF -> paths (see the module's rules for ``package://``)."""

    def __init__(self, urdf: Path, packages: Mapping[str, Path]) -> None:
        self.urdf = urdf
        self.packages = packages
        self._found: dict[str, Path] = {}

    def resolve(self, filename: str, line: int | None) -> Path:
        if not filename:
            raise ConfigError(self.urdf, "<mesh> has no filename", where=line)
        if filename.startswith("package://"):
            return self._package_file(filename, line)
        if filename.startswith("file://"):
            filename = filename.removeprefix("file://")
        elif "://" in filename:
            raise ConfigError(self.urdf, f"mesh filename '{filename}' is a URL; give a file (relative to the URDF, "
                              "absolute, file:// or package://)", where=line)
        return self.urdf.parent / filename

    def _package_file(self, filename: str, line: int | None) -> Path:
        name, _, rest = filename.removeprefix("package://").partition("/")
        try:
            relative = check_relative_name(rest, source=self.urdf, what=f"mesh '{filename}': its path")
        except InputError as exc:
            raise ConfigError(self.urdf, exc.problem, where=line) from None
        folder = self._package_folder(name)
        if folder is None:
            raise ConfigError(self.urdf, f"mesh '{filename}': no package '{name}' found (looked for a folder of that "
                              "name, or holding a package.xml that names it, above the URDF and beside those "
                              f"folders); map it to a folder in the scene: 'packages: {{{name}: FOLDER}}'", where=line)
        return folder / relative

    def _package_folder(self, name: str) -> Path | None:
        if name in self.packages:
            return self.packages[name]
        if name not in self._found:
            found = _find_package(self.urdf.resolve().parent, name)
            if found is None:
                return None
            log.info("package://%s/ resolved to %s", name, found)
            self._found[name] = found
        return self._found[name]


def _find_package(start: Path, name: str) -> Path | None:
    if not name or name in (".", ".."):
        return None
    ancestors = [start, *start.parents][:PACKAGE_SEARCH_DEPTH]
    for folder in ancestors:
        if folder.name == name or _package_xml_name(folder) == name:
            return folder
    for folder in ancestors:
        beside = folder / name
        if beside.is_dir():
            return beside
    return None


def _package_xml_name(folder: Path) -> str | None:
    manifest = folder / "package.xml"
    if not manifest.is_file():
        return None
    try:  # bounded, a regular file (a FIFO named package.xml is not one)
        text = read_user_file(manifest, 1 << 20).decode("utf-8", errors="replace")
    except InputError:
        return None
    match = _PACKAGE_NAME.search(text)
    return match.group(1) if match else None
