"""The files a mesh file names (materials, texture images, glTF buffers), read and checked before any decoder sees
them, and the mesh's size checked against what it declares.

A mesh is often not one file: an OBJ names ``.mtl`` material files (``mtllib``) that name texture images
(``map_Kd``), a glTF names buffers and images, a COLLADA file and a PLY name images. Every one of them is read here,
once, by the one bounded reader (:mod:`bt_grasp.files.bounded_io`):

- **inside the mesh's folder**: a name is read as the format writes it (``%20``, ``file://``, ``./``, backslashes)
  and must stay in the mesh's folder, links resolved (:func:`bt_grasp.files.safe_path.join_under`); an absolute
  name, a drive, ``..`` or a URL is never opened, not even looked at (whether such a file exists is nobody's
  business: a texture named so is drawn in its material's colour, like a missing one);
- **regular files of a bounded size**: a FIFO, a device or a file over its kind's limit is one sentence;
- **pictures sized before decoding**: a texture must say at most
  :data:`~bt_grasp.files.image_header.MAX_TEXTURE_SIDE` pixels a side in its header (a 431 KB PNG declaring
  20000 x 20000 took 5.3 GB in the renderer);
- **counts checked against the bytes present and the caps** (:data:`MAX_MESH_FACES`, :data:`MAX_MESH_VERTICES`)
  before a parser allocates anything: an OBJ's face statements, a binary STL's or a PLY's declared counts, a glTF's
  accessor counts.

Decoders then get only these bytes: trimesh through :class:`CheckedFiles` (a resolver that serves the checked
bytes and never touches the disk), the renderer through :func:`renderer_copy` (the files with every name in them
rewritten to the checked copies' names, written to a private folder by ``bt_grasp.sim``).
"""

from __future__ import annotations

import base64
import binascii
import json
import os
import posixpath
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import unquote

from bt_grasp.errors import ConfigError, InputError
from bt_grasp.files.bounded_io import MAX_IMAGE_BYTES, MAX_MATERIAL_BYTES, MAX_MESH_BYTES, read_user_file
from bt_grasp.files.image_header import MAX_TEXTURE_SIDE, picture_size
from bt_grasp.files.safe_path import check_relative_name, join_under

#: the most triangles and vertices a mesh file may hold (an OBJ of 3 million faces took 680 MB and 7 s to parse;
#: 5 million passed validation, then sat in the convex decomposition for ever)
MAX_MESH_FACES = 2_000_000
MAX_MESH_VERTICES = 2_000_000
#: the most pieces (an OBJ's objects, groups and material switches, a glTF's meshes, primitives and nodes, a COLLADA
#: file's geometries and nodes) a mesh may have: an 18 MB OBJ of 200,000 one-triangle objects kept trimesh busy past
#: 5 minutes
MAX_MESH_PIECES = 1000
#: the most files one mesh may name (materials, textures, buffers, counted together), and their total size
MAX_NAMED_FILES = 64
MAX_NAMED_BYTES = 256 << 20

_MTL_MAPS = re.compile(r"^[ \t]*(map_\w+|bump|disp|decal|refl|norm)[ \t]+(.+?)[ \t]*$", re.MULTILINE | re.IGNORECASE)
_DAE_IMAGE = re.compile(r"(<image\b[^>]*>\s*<init_from>\s*(?:<ref>\s*)?)([^<]+?)(\s*(?:</ref>\s*)?</init_from>)",
                        re.IGNORECASE)
_DAE_ANY_REF = re.compile(r"<(init_from|ref)>\s*([^<]*?)\s*</\1>", re.IGNORECASE)
_PLY_TEXTURE = re.compile(rb"^(comment[ \t]+TextureFile[ \t]+)(.+?)[ \t]*$", re.MULTILINE | re.IGNORECASE)
#: the statements of an OBJ and an MTL file that never name a file: a copy for the renderer keeps these and the
#: rewritten names, nothing else (a statement it does not know could name a file a reader would open)
_OBJ_KEPT = frozenset({"v", "vt", "vn", "vp", "f", "l", "p", "o", "g", "s", "usemtl", "mg", "cstype", "deg", "curv",
                       "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "bmat", "step", "lod",
                       "shadow_obj", "trace_obj", "ctech", "stech", "bevel", "c_interp", "d_interp"})
_MTL_KEPT = frozenset({"newmtl", "ka", "kd", "ks", "ke", "ns", "ni", "d", "tr", "tf", "illum", "sharpness", "pr",
                       "pm", "ps", "pc", "pcr", "aniso", "anisor", "km"})


@dataclass(frozen=True)
class Reference:
    """A file named by one of a mesh's files: ``kind`` (material, texture, buffer), the name as written (``raw``),
    and the file that names it (``origin``, a name in :attr:`MeshFiles.files`)."""

    kind: str
    raw: str
    origin: str


@dataclass
class MeshFiles:
    """A mesh file and the files it names, read and checked. ``files``: name (relative to the mesh's folder) ->
    bytes, the mesh itself first; ``read``: each reference read -> its name in ``files``; ``missing``: named files
    inside the folder that are not there, with their names (textures and materials: the mesh is drawn without
    them); ``outside``:
    references that leave the folder (never opened); ``unstageable``: why the renderer cannot be given a copy of the
    files ('' when it can)."""

    path: Path
    main: str
    files: dict[str, bytes] = field(default_factory=dict)
    read: dict[Reference, str] = field(default_factory=dict)
    missing: list[tuple[Reference, str]] = field(default_factory=list)
    outside: list[Reference] = field(default_factory=list)
    unstageable: str = ""

    @property
    def textures(self) -> list[str]:
        return [name for ref, name in self.read.items() if ref.kind == "texture"]

    def name_of(self, raw: str) -> str | None:
        """The checked file a name as written in any of the files stands for (what a decoder asks for)."""
        for ref, name in self.read.items():
            if ref.raw.strip() == raw.strip():
                return name
        cleaned = _clean(raw)
        return cleaned if cleaned in self.files else None


ErrorFactory = Callable[[str], ConfigError]


def _clean(raw: str) -> str:
    """A name as the mesh formats mean it: ``%20`` escapes decoded, a ``file://`` prefix and ``./`` parts dropped,
    backslashes read as separators (exporters on Windows write them)."""
    text = unquote(raw.strip().removeprefix("file://")).replace("\\", "/")
    return "/".join(part for part in text.split("/") if part not in ("", ".")) if not text.startswith("/") else text


def _resolve(folder: Path, origin: str, raw: str, source: Path) -> str | None:
    """The name (relative to ``folder``, the mesh's) of the file ``raw`` names from the file ``origin``, or None
    when it leaves the folder (absolute, a drive, ``..`` out of it, a URL, a link out of it)."""
    text = unquote(raw.strip().removeprefix("file://")).replace("\\", "/")
    if "://" in text or text.startswith("/") or re.match(r"^[A-Za-z]:", text) or text.startswith("~"):
        return None
    joined = posixpath.normpath(posixpath.join(posixpath.dirname(origin), text))
    if joined in ("", ".") or joined.startswith("../") or joined == "..":
        return None
    try:
        check_relative_name(joined, source=source)
        join_under(folder, joined, source=source)
    except InputError:
        return None
    return joined


def read_mesh_files(path: Path, data: bytes, error: ErrorFactory) -> MeshFiles:
    """``path`` (whose bytes are ``data``) and every file it names, read and checked (see the module's rules);
    ``error(problem)`` makes the sentence (the caller names the scene, the line and the object)."""
    check_counts(path, data, error)
    found = MeshFiles(path, path.name, {path.name: data})
    folder = path.parent
    queue = references(path.name, data, path.suffix.lower(), found, error)
    total = len(data)
    while queue:
        ref = queue.pop(0)
        name = _resolve(folder, ref.origin, ref.raw, path)
        if name is None:
            if ref.kind == "buffer":
                raise error(f"names buffer {ref.raw[:120]!r}, outside its folder {folder}: a mesh may name only "
                            "files beside it")
            found.outside.append(ref)
            continue
        if name in found.files:
            found.read[ref] = name
            continue
        target = folder / name
        if not os.path.lexists(target):
            if ref.kind == "buffer":
                raise error(f"names buffer '{name}', which is missing ({folder})")
            found.missing.append((ref, name))
            continue
        if len(found.files) > MAX_NAMED_FILES:
            raise error(f"names more than {MAX_NAMED_FILES} files (materials, textures, buffers)")
        limit = {"material": MAX_MATERIAL_BYTES, "texture": MAX_IMAGE_BYTES}.get(ref.kind, MAX_MESH_BYTES)
        try:
            content = read_user_file(target, limit, error=ConfigError, within=folder)
        except ConfigError as exc:
            raise error(f"its {ref.kind} file '{target}' {_problem_text(exc.problem)}") from None
        total += len(content)
        if total > MAX_NAMED_BYTES:
            raise error(f"names files of more than {MAX_NAMED_BYTES} bytes in all")
        if ref.kind == "texture":
            check_picture(content, f"texture image '{target}'", error)
        found.files[name] = content
        found.read[ref] = name
        if ref.kind == "material":
            queue += references(name, content, ".mtl", found, error)
    return found


def _problem_text(problem: str) -> str:
    """A bounded reader's problem as the rest of a sentence about a named file ("is not a regular file ...")."""
    return problem if problem.startswith(("is ", "lies ")) else f"cannot be read: {problem}"


def check_picture(data: bytes, what: str, error: ErrorFactory) -> None:
    """A texture image whose header says at most :data:`MAX_TEXTURE_SIDE` pixels a side (nothing is decoded)."""
    size = picture_size(data)
    if size is None:
        raise error(f"{what} is not a picture that can be sized from its header (PNG, JPEG, or another format "
                    "Pillow reads), or says more pixels than Pillow's decompression-bomb limit")
    if max(size) > MAX_TEXTURE_SIDE or min(size) < 1:
        raise error(f"{what} is {size[0]} x {size[1]} pixels; a texture may have at most {MAX_TEXTURE_SIDE} a side "
                    "(sized from its header, before anything is decoded)")


# -- the names in each format ----------------------------------------------------------------------------------

def references(origin: str, data: bytes, suffix: str, found: MeshFiles, error: ErrorFactory) -> list[Reference]:
    """The files ``data`` (the file ``origin``, of format ``suffix``) names. Pictures embedded in a glTF or GLB
    file are sized here; a COLLADA file naming pictures in a way this reader does not know cannot be copied for
    the renderer (:attr:`MeshFiles.unstageable`)."""
    if suffix == ".obj":
        return [Reference("material", line[6:].strip(), origin) for line in _text(data).splitlines()
                if line.startswith("mtllib") and line[6:7].isspace() and line[6:].strip()]
    if suffix == ".mtl":
        return [Reference("texture", map_file(rest), origin) for _key, rest in _MTL_MAPS.findall(_text(data))]
    if suffix == ".dae":
        text = _text(data)
        images = [m.group(2) for m in _DAE_IMAGE.finditer(text)]
        other = [v for _tag, v in _DAE_ANY_REF.findall(text) if v and v not in images and _looks_like_a_file(v)]
        if other:
            found.unstageable = f"it names '{other[0][:80]}' in a way bt_grasp cannot check"
        return [Reference("texture", name, origin) for name in images if not name.startswith("data:")]
    if suffix == ".ply":
        header = data[: data.find(b"end_header")] if b"end_header" in data else data[:4096]
        return [Reference("texture", m.group(2).decode("utf-8", "replace"), origin)
                for m in _PLY_TEXTURE.finditer(header)]
    if suffix in (".gltf", ".glb"):
        document, binary = _gltf_document(data, suffix, error)
        refs = []
        for kind, key in (("buffer", "buffers"), ("texture", "images")):
            for index, item in enumerate(_list(document.get(key))):
                uri = item.get("uri") if isinstance(item, dict) else None
                if isinstance(uri, str) and uri.startswith("data:"):
                    if kind == "texture":
                        check_picture(_data_uri(uri, error), f"embedded image {index}", error)
                elif isinstance(uri, str):
                    refs.append(Reference(kind, uri, origin))
                elif kind == "texture" and isinstance(item, dict) and binary is not None:
                    check_picture(_buffer_view(document, item.get("bufferView"), binary),
                                  f"embedded image {index}", error)
        return refs
    return []


def _looks_like_a_file(value: str) -> bool:
    return "/" in value or "\\" in value or ":" in value or bool(re.search(r"\.\w{2,5}$", value))


def _text(data: bytes) -> str:
    return data.decode("utf-8", errors="replace")


def _list(value: Any) -> list[Any]:
    return value if isinstance(value, list) else []


def map_file(rest: str) -> str:
    """The file name of an MTL map statement's arguments: options (``-bm 1``, ``-o 0 0 0``, ``-clamp on``,
    ``-imfchan l``) come first; the rest, spaces and all, is the name."""
    words = rest.split()
    i = _options_end(words)
    return " ".join(words[i:]) or words[-1]


def _options_end(words: list[str]) -> int:
    i = 0
    while i < len(words) and words[i].startswith("-"):
        takes_word = words[i] in ("-imfchan", "-type", "-clamp", "-blendu", "-blendv", "-cc")
        i += 1
        if takes_word:
            i += 1
            continue
        while i < len(words) and _is_number(words[i]):
            i += 1
    return i


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _gltf_document(data: bytes, suffix: str, error: ErrorFactory) -> tuple[dict[str, Any], bytes | None]:
    """A glTF's JSON (and a GLB's binary chunk), its declared lengths checked against the bytes present."""
    binary = None
    if suffix == ".glb":
        if len(data) < 20 or data[:4] != b"glTF":
            raise error("is not a GLB file (no 'glTF' header)")
        _magic, _version, length = struct.unpack_from("<4sII", data, 0)
        chunk_length, chunk_type = struct.unpack_from("<I4s", data, 12)
        if length > len(data) or 20 + chunk_length > len(data) or chunk_type != b"JSON":
            raise error(f"declares {length} bytes and a JSON chunk of {chunk_length}, but holds {len(data)}")
        text = data[20:20 + chunk_length]
        rest = 20 + chunk_length
        if rest + 8 <= len(data):
            bin_length, bin_type = struct.unpack_from("<I4s", data, rest)
            if bin_type == b"BIN\x00":
                if rest + 8 + bin_length > len(data):
                    raise error(f"declares a binary chunk of {bin_length} bytes, but holds {len(data) - rest - 8}")
                binary = data[rest + 8:rest + 8 + bin_length]
    else:
        text = data
    try:
        document = json.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise error("is not a glTF file (its JSON cannot be read)") from None
    if not isinstance(document, dict):
        raise error("is not a glTF file (its JSON is not an object)")
    meshes = _list(document.get("meshes"))
    pieces = len(_list(document.get("nodes"))) + sum(
        len(_list(m.get("primitives"))) if isinstance(m, dict) else 1 for m in meshes)
    if pieces > MAX_MESH_PIECES:
        raise error(f"has {pieces:,} nodes and primitives, more than the {MAX_MESH_PIECES:,} pieces a mesh may have")
    for index, accessor in enumerate(_list(document.get("accessors"))):
        count = accessor.get("count") if isinstance(accessor, dict) else None
        if isinstance(count, int) and not 0 <= count <= 3 * MAX_MESH_FACES:
            raise error(f"declares {count:,} elements in accessor {index}, more than a mesh of {MAX_MESH_FACES:,} "
                        "triangles holds")
    return document, binary


def _buffer_view(document: dict[str, Any], index: Any, binary: bytes) -> bytes:
    views = _list(document.get("bufferViews"))
    view = views[index] if isinstance(index, int) and 0 <= index < len(views) else None
    if not isinstance(view, dict):
        return b""
    offset, length = view.get("byteOffset", 0), view.get("byteLength", 0)
    if not (isinstance(offset, int) and isinstance(length, int)) or offset < 0 or length < 0:
        return b""
    return binary[offset:offset + length]


def _data_uri(uri: str, error: ErrorFactory) -> bytes:
    head, _, payload = uri.partition(",")
    try:
        return base64.b64decode(payload, validate=False) if head.endswith(";base64") else unquote(payload).encode()
    except (binascii.Error, ValueError):
        raise error("holds an embedded picture that is not base64") from None


# -- counts against caps and bytes --------------------------------------------------------------------------------

def check_counts(path: Path, data: bytes, error: ErrorFactory) -> None:
    """Refuse a mesh whose face or vertex statements (or declared counts) exceed :data:`MAX_MESH_FACES` /
    :data:`MAX_MESH_VERTICES`, or whose declared counts need more bytes than the file holds, before it is parsed."""
    suffix = path.suffix.lower()
    faces = vertices = pieces = 0
    if suffix == ".obj":
        faces = data.count(b"\nf ") + data.startswith(b"f ") + data.count(b"\nf\t")
        vertices = data.count(b"\nv ") + data.startswith(b"v ") + data.count(b"\nv\t")
        pieces = sum(data.count(b"\n" + key) + data.startswith(key) for key in (b"o ", b"g ", b"usemtl"))
    elif suffix == ".dae":
        pieces = data.count(b"<geometry") + data.count(b"<node")
    elif suffix == ".stl":  # binary when its declared count fits its length exactly (trimesh's own test)
        declared = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else -1
        faces = declared if 84 + 50 * declared == len(data) else data.count(b"endfacet")
    elif suffix == ".ply":
        end = data.find(b"end_header")
        header = _text(data[: end if end >= 0 else 4096])
        for kind, count in re.findall(r"^element\s+(\w+)\s+(\d+)", header, re.MULTILINE):
            number = int(count) if len(count) < 20 else 10**20
            if number > len(data):
                raise error(f"declares {number:,} {kind} elements, more than its {len(data):,} bytes can hold")
            if kind == "face":
                faces = number
            elif kind == "vertex":
                vertices = number
    if faces > MAX_MESH_FACES:
        raise error(f"has at least {faces:,} triangles, more than the {MAX_MESH_FACES:,} a mesh may have "
                    "(simplify it first)")
    if pieces > MAX_MESH_PIECES:
        raise error(f"has {pieces:,} pieces (objects, groups, material switches, geometries, nodes), more than the "
                    f"{MAX_MESH_PIECES:,} a mesh may have")
    if vertices > MAX_MESH_VERTICES:
        raise error(f"has at least {vertices:,} vertices, more than the {MAX_MESH_VERTICES:,} a mesh may have "
                    "(simplify it first)")


# -- decoders get only these bytes ----------------------------------------------------------------------------------

def checked_resolver(found: MeshFiles) -> Any:
    """A trimesh resolver over the checked files: it serves their bytes by the names the files use and never
    touches the disk (a name not read here is 'not found': the decoder goes on without it)."""
    import trimesh

    class CheckedFiles(trimesh.resolvers.Resolver):
        def __init__(self) -> None:
            self.file_name = found.main

        def get(self, key: str) -> bytes:
            name = found.name_of(key)
            if name is None:
                raise FileNotFoundError(key)
            return found.files[name]

        def write(self, name: str, data: Any) -> None:
            raise OSError("bt_grasp reads meshes, it writes nothing beside them")

        def namespaced(self, namespace: str) -> CheckedFiles:
            return self

        def keys(self) -> list[str]:
            return list(found.files)

    return CheckedFiles()


def renderer_copy(found: MeshFiles) -> tuple[tuple[str, bytes], ...]:
    """The files to give the renderer, the mesh first: each as checked, with every name in it rewritten to the
    checked copy's name (names that were not read are dropped), and the statements of an OBJ or MTL file that
    could name a file but were not read left out. ``()`` when the mesh cannot be copied so
    (:attr:`MeshFiles.unstageable`)."""
    if found.unstageable:
        return ()
    kinds = {name: ref.kind for ref, name in found.read.items()}
    out: list[tuple[str, bytes]] = []
    for name, data in found.files.items():
        # a file is rewritten as what it was read as (a material file is one whatever its name ends with)
        suffix = found.path.suffix.lower() if name == found.main else {"material": ".mtl"}.get(kinds.get(name, ""), "")
        out.append((name, _rewritten(name, data, suffix, found)))
    return tuple(out)


def _rewritten(origin: str, data: bytes, suffix: str, found: MeshFiles) -> bytes:
    def target(kind: str, raw: str) -> str | None:
        name = found.read.get(Reference(kind, raw, origin))
        return None if name is None else posixpath.relpath(name, posixpath.dirname(origin) or ".")

    if suffix == ".obj" and origin == found.main:
        lines = []
        original = _text(data).splitlines()
        for line in original:
            key = line.split(maxsplit=1)[0] if line.split() else ""
            if key == "mtllib":
                name = target("material", line[6:].strip())
                if name is not None:
                    lines.append(f"mtllib {name}")
            elif key.lower() in _OBJ_KEPT or key.startswith("#") or not key:
                lines.append(line)
        return data if lines == original else ("\n".join(lines) + "\n").encode()
    if suffix == ".mtl":
        lines = []
        original = _text(data).splitlines()
        for line in original:
            words = line.split()
            key = words[0].lower() if words else ""
            match = _MTL_MAPS.match(line)
            if match:
                rest = match.group(2)
                name = target("texture", map_file(rest))
                if name is not None:
                    options = rest.split()[: _options_end(rest.split())]
                    lines.append(" ".join([match.group(1), *options, name]))
            elif key in _MTL_KEPT or key.startswith("#") or not key:
                lines.append(line)
        return data if lines == original else ("\n".join(lines) + "\n").encode()
    if suffix == ".dae" and origin == found.main:
        def swap(match: re.Match[str]) -> str:
            name = target("texture", match.group(2))
            return match.group(1) + (name if name is not None else "missing.png") + match.group(3)

        return _DAE_IMAGE.sub(swap, _text(data)).encode()
    if suffix == ".ply" and origin == found.main:
        end = data.find(b"end_header")
        if end < 0:
            return data
        header = _PLY_TEXTURE.sub(lambda m: m.group(1) + (target("texture", m.group(2).decode("utf-8", "replace"))
                                                          or "missing.png").encode(), data[:end])
        return header + data[end:]
    if suffix in (".gltf", ".glb") and origin == found.main:
        return _gltf_rewritten(data, suffix, lambda kind, raw: target(kind, raw))
    return data


def _gltf_rewritten(data: bytes, suffix: str, target: Callable[[str, str], str | None]) -> bytes:
    def fix(document: dict[str, Any]) -> dict[str, Any]:
        for kind, key in (("buffer", "buffers"), ("texture", "images")):
            for item in _list(document.get(key)):
                uri = item.get("uri") if isinstance(item, dict) else None
                if isinstance(uri, str) and not uri.startswith("data:"):
                    item["uri"] = target(kind, uri) or "missing.png"
        return document

    if suffix == ".gltf":
        return json.dumps(fix(json.loads(data.decode("utf-8")))).encode()
    chunk_length = struct.unpack_from("<I", data, 12)[0]
    document = fix(json.loads(data[20:20 + chunk_length].decode("utf-8")))
    if not any(isinstance(b, dict) and "uri" in b for key in ("buffers", "images") for b in _list(document.get(key))):
        return data
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + chunk_length:]
    body = struct.pack("<I4s", len(text), b"JSON") + text + rest
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body
