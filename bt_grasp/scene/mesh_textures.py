"""The texture images a mesh file's materials name, and which of them are missing.

The renderer refuses a whole mesh when one image its materials name is not on disk (SAPIEN: "filesystem error:
cannot make canonical path"), and object sets are often copied without them (an OBJ whose ``.mtl`` names a
``texture_map.png`` left behind). The scene loader asks here first and draws such a mesh in its material's
colour instead. Read: an OBJ's ``mtllib`` files (``map_*``, ``bump``, ``disp``, ``decal``, ``refl``, ``norm``),
a COLLADA file's ``<image><init_from>``, a glTF file's image ``uri``s. Nothing is written; every file read is
bounded.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from urllib.parse import unquote

from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file

#: the largest material file read, bytes
MAX_MTL_BYTES = 4 << 20
_MTL_MAPS = re.compile(r"^\s*(map_\w+|bump|disp|decal|refl|norm)\s+(.+?)\s*$", re.MULTILINE | re.IGNORECASE)
_DAE_IMAGE = re.compile(r"<image\b[^>]*>\s*<init_from>\s*([^<]+?)\s*</init_from>", re.IGNORECASE)


def texture_files(path: Path, data: bytes) -> list[Path]:
    """The image files ``path`` (whose bytes are ``data``) names through its materials."""
    suffix = path.suffix.lower()
    text = data.decode("utf-8", errors="replace")
    if suffix == ".obj":
        return _obj_textures(path, text)
    if suffix == ".dae":
        return [_local(path.parent, name) for name in _DAE_IMAGE.findall(text) if not name.startswith("data:")]
    if suffix == ".gltf":
        return _gltf_textures(path, text)
    return []


def missing_textures(path: Path, data: bytes) -> list[Path]:
    """The texture images ``path`` names that are not files on disk."""
    return [p for p in texture_files(path, data) if not p.is_file()]


def _local(folder: Path, name: str) -> Path:
    return folder / unquote(name.removeprefix("file://")).replace("\\", "/")


def _obj_textures(path: Path, text: str) -> list[Path]:
    found: list[Path] = []
    for line in text.splitlines():
        if not line.startswith("mtllib"):
            continue
        mtl = path.parent / line.removeprefix("mtllib").strip()
        try:
            mtl_text = read_user_file(mtl, MAX_MTL_BYTES).decode("utf-8", errors="replace")
        except InputError:
            continue  # a missing material file: the renderer draws the mesh without it
        for _key, rest in _MTL_MAPS.findall(mtl_text):
            found.append(_local(mtl.parent, _map_file(rest)))
    return found


def _map_file(rest: str) -> str:
    """The file name of an MTL map statement's arguments: options (``-bm 1``, ``-o 0 0 0``, ``-clamp on``,
    ``-imfchan l``) come first; the rest, spaces and all, is the name."""
    words = rest.split()
    i = 0
    while i < len(words) and words[i].startswith("-"):
        takes_word = words[i] in ("-imfchan", "-type", "-clamp", "-blendu", "-blendv", "-cc")
        i += 1
        if takes_word:
            i += 1
            continue
        while i < len(words) and _is_number(words[i]):
            i += 1
    return " ".join(words[i:]) or words[-1]


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _gltf_textures(path: Path, text: str) -> list[Path]:
    try:
        images = json.loads(text).get("images", [])
    except (ValueError, AttributeError):
        return []
    uris = [im.get("uri") for im in images if isinstance(im, dict)]
    return [_local(path.parent, u) for u in uris if isinstance(u, str) and not u.startswith("data:")]
