"""The surfaces issue 42 added to the fuzz suite (``tools/fuzz_inputs.py`` runs them): files a mesh names, URDF trees,
collision-cache entries, ONNX models, control messages, resident requests and crafted ``replay --resim`` logs.

Each surface has a few mutation kinds. ``make_*`` writes one case's files into its own folder (in the parent
process) and returns the command the worker runs: a ``bt-grasp`` command line, or ``["@surface", ...]`` for the
surfaces that are not a command (``run_*`` here, in the worker process, answering as a command would: an exit code
and stderr). A name that leaves a case's folder points at the job's *trap*: a regular file whose access time is
set to 1970 (any read moves it: the mount is ``relatime``) and a FIFO (any blocking open hangs, and the case's
alarm fails it).
"""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import random
import struct
import time
import zlib
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
BOX_OBJ = (REPO / "tests" / "data" / "meshes" / "box.obj").read_text()
SHORT_TREE = ('<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T"><AlwaysSuccess/>'
              "</BehaviorTree></root>")

MESH_KINDS = ("obj_names", "gltf_buffers", "glb_chunks", "ply_header", "stl_count", "dae_images", "mesh_bytes",
              "scale", "texture_picture", "pieces")
URDF_KINDS = ("chain", "links", "numbers", "xml", "mesh_names")
CACHE_KINDS = ("volume", "parts", "archive", "folder")
MODEL_KINDS = ("shape_bomb", "protobuf_bytes", "metadata", "external_data", "special_file")
CONTROL_KINDS = ("command_json", "parameters", "files", "breakpoints")
RESIDENT_KINDS = ("frames", "requests")
RESIM_KINDS = ("outside_names", "texture_bomb", "attachment_names", "interventions", "mesh_damage")


# ---------------------------------------------------------------- helpers
def png(width: int, height: int, rows: int = 1) -> bytes:
    """A PNG whose header says ``width`` x ``height`` (RGB) holding ``rows`` rows of zeros."""
    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    raw = zlib.compress(b"\x00" * (1 + 3 * min(width, 4096)) * rows, 9)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", raw) + chunk(b"IEND", b""))


def make_trap(folder: Path) -> dict[str, Path]:
    """The job's trap (see the module): what no case may read."""
    folder.mkdir(parents=True, exist_ok=True)
    secret = folder / "secret.png"
    secret.write_bytes(png(4, 4, 4))
    fifo = folder / "fifo.png"
    if not fifo.exists():
        os.mkfifo(fifo)
    os.utime(secret, (0, time.time()))
    return {"secret": secret, "fifo": fifo}


def trap_was_read(trap: dict[str, Path]) -> bool:
    return os.stat(trap["secret"]).st_atime > 1.0


def _hostile_name(rng: random.Random, trap: dict[str, Path], folder: Path) -> str:
    """A file name as a hostile mesh writes it: outside its folder (absolute, ``..``, a URL, a drive), or inside
    it but a FIFO, a sparse huge file, missing, or odd (``%2e%2e``, control characters, very long)."""
    roll = rng.randrange(12)
    if roll == 0:
        return str(trap["secret"])
    if roll == 1:
        return str(trap["fifo"])
    if roll == 2:
        return "../" * rng.randint(1, 6) + "secret.png"
    if roll == 3:
        return "file://" + str(trap["secret"])
    if roll == 4:
        return "%2e%2e/%2e%2e/" + trap["secret"].name
    if roll == 5:
        return rng.choice(["C:\\textures\\wood.png", "\\\\host\\share\\x.png", "http://example.invalid/x.png"])
    if roll == 6:
        name = "fifo_here.png"
        if not (folder / name).exists():
            os.mkfifo(folder / name)
        return name
    if roll == 7:
        name = "sparse.bin"
        with (folder / name).open("wb") as f:
            f.truncate(rng.choice([5 << 20, 300 << 20, 3 << 30]))
        return name
    if roll == 8:
        return rng.choice(["missing.png", "sub/../missing.png", "./a b.png", ""])
    if roll == 9:
        return rng.choice(["x" * 300, "a\x00b.png", "\x1b[2J.png", "a\nb.png", "\u202etxt.png"])
    if roll == 10:
        (folder / "link.png").unlink(missing_ok=True)
        (folder / "link.png").symlink_to(trap["secret"])
        return "link.png"
    (folder / "ok.png").write_bytes(png(8, 8, 8))
    return "ok.png"


def _scene(folder: Path, mesh: str, shape: str = "mesh", scale: str = "") -> Path:
    scene = folder / "scene.yaml"
    key = "mesh" if shape == "mesh" else "urdf"
    scene.write_text(f"version: 2\nobjects:\n  - name: thing\n    shape: {shape}\n    {key}: {json.dumps(mesh)}\n"
                     + (f"    scale: {scale}\n" if scale else "") + "    pose: {xy_m: [0.5, 0.0]}\n")
    return scene


def _box_gltf() -> tuple[dict[str, Any], bytes]:
    """A 4 cm box as a glTF document with its one buffer."""
    import trimesh
    from trimesh.exchange.gltf import export_gltf

    files = export_gltf(trimesh.Scene(trimesh.creation.box(extents=(0.04, 0.04, 0.04))), merge_buffers=True)
    document = json.loads(files["model.gltf"])
    return document, files[document["buffers"][0]["uri"]]


def _flip(data: bytes, rng: random.Random, flips: int) -> bytes:
    buf = bytearray(data)
    for _ in range(flips):
        i = rng.randrange(len(buf))
        buf[i] ^= 1 << rng.randrange(8)
    return bytes(buf)


# ---------------------------------------------------------------- meshes and the files they name
def make_mesh(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    """A scene whose mesh object (or the files the mesh names) is hostile; `scene validate` reads it all."""
    if kind == "obj_names":
        mtl = _hostile_name(rng, trap, folder) if rng.random() < 0.4 else "part.mtl"
        (folder / "part.obj").write_text(f"mtllib {mtl}\nusemtl m\n" + BOX_OBJ)
        if mtl == "part.mtl":
            maps = [f"{rng.choice(['map_Kd', 'map_Ks', 'bump', 'norm', 'map_Kd -o 1 1 1'])} "
                    f"{_hostile_name(rng, trap, folder)}" for _ in range(rng.randint(1, 4))]
            (folder / "part.mtl").write_text("newmtl m\nKd 0.5 0.5 0.5\n" + "\n".join(maps) + "\n")
        return ["scene", "validate", str(_scene(folder, "part.obj"))]
    if kind in ("gltf_buffers", "glb_chunks"):
        document, buffer = _box_gltf()
        roll = rng.randrange(4)
        if roll == 0:
            document["buffers"][0]["uri"] = _hostile_name(rng, trap, folder)
        elif roll == 1:
            document["accessors"][rng.randrange(len(document["accessors"]))]["count"] = rng.choice(
                [10**7, 10**9, 2**31 - 1, -1])
        elif roll == 2:
            document["images"] = [{"uri": rng.choice([_hostile_name(rng, trap, folder),
                                                      "data:image/png;base64," + base64.b64encode(
                                                          png(30_000, 30_000)).decode()])}]
        else:
            document["buffers"][0]["byteLength"] = rng.choice([10**12, 0, 7])
        if kind == "gltf_buffers":
            if document["buffers"][0]["uri"].startswith("data:") is False and roll != 0:
                (folder / document["buffers"][0]["uri"]).write_bytes(buffer)
            (folder / "part.gltf").write_text(json.dumps(document))
            return ["scene", "validate", str(_scene(folder, "part.gltf"))]
        document["buffers"][0].pop("uri", None)
        text = json.dumps(document).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(buffer), b"BIN\x00") + buffer
        data = bytearray(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
        if rng.random() < 0.5:  # a declared length set huge
            struct.pack_into("<I", data, rng.choice([8, 12, 20 + len(text)]), rng.choice([2**31, 2**32 - 1, 10**6]))
        (folder / "part.glb").write_bytes(bytes(data))
        return ["scene", "validate", str(_scene(folder, "part.glb"))]
    if kind == "ply_header":
        count = rng.choice([10**9, 2**63, 3 * 10**6, 8, -5])
        face_count = rng.choice([10**9, 12, 2**40])
        header = (f"ply\nformat {rng.choice(['ascii', 'binary_little_endian'])} 1.0\n"
                  f"comment TextureFile {_hostile_name(rng, trap, folder)}\nelement vertex {count}\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  f"element face {face_count}\nproperty list uchar int vertex_indices\nend_header\n")
        (folder / "part.ply").write_bytes(header.encode() + rng.randbytes(rng.randint(0, 400)))
        return ["scene", "validate", str(_scene(folder, "part.ply"))]
    if kind == "stl_count":
        count = rng.choice([10**9, 2**32 - 1, 5_000_000, 12])
        body = rng.randbytes(50 * rng.randint(0, 20))
        (folder / "part.stl").write_bytes(b"\x00" * 80 + struct.pack("<I", count) + body)
        return ["scene", "validate", str(_scene(folder, "part.stl"))]
    if kind == "dae_images":
        name = _hostile_name(rng, trap, folder)
        toy = (REPO / "tests/data/meshes/ros_style/meshes/toy.dae").read_text()
        image = (f'<library_images><image id="t"><init_from>{name}</init_from></image></library_images>'
                 if rng.random() < 0.7 else '<!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>')
        text = toy.replace("<library_geometries>", image + "<library_geometries>", 1) if "<!DOCTYPE" not in image \
            else toy.replace("<COLLADA", image + "<COLLADA", 1)
        (folder / "part.dae").write_text(text)
        return ["scene", "validate", str(_scene(folder, "part.dae", scale="0.001"))]  # the toy is in millimetres
    if kind == "mesh_bytes":
        base = rng.choice(["obj", "stl", "gltf"])
        if base == "obj":
            data = BOX_OBJ.encode()
        elif base == "stl":
            data = (REPO / "tests/data/meshes/box.stl").read_bytes()
        else:
            document, buffer = _box_gltf()
            document["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()
            data = json.dumps(document).encode()
        data = _flip(data, rng, rng.randint(1, 40)) if rng.random() < 0.7 else data[: rng.randrange(len(data))]
        (folder / f"part.{base}").write_bytes(data)
        return ["scene", "validate", str(_scene(folder, f"part.{base}"))]
    if kind == "scale":
        (folder / "part.obj").write_text(BOX_OBJ)
        scale = rng.choice(["1e308", "-1e308", "1e-308", "5e-324", "[1e308, 1, 1]", "[1, 0, 1]", ".nan", ".inf",
                            "1e400", "[1, 1]"])
        return ["scene", "validate", str(_scene(folder, "part.obj", scale=scale))]
    if kind == "pieces":  # many objects, or one mesh placed by many nodes
        n = rng.choice([300, 1001, 50_000])
        if rng.random() < 0.5:
            lines = [f"o p{i}\nv {i * 1e-5} 0 0\nv {i * 1e-5} 0.01 0\nv {i * 1e-5} 0 0.01\n"
                     f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}" for i in range(n)]
            (folder / "part.obj").write_text("\n".join(lines) + "\n")
            return ["scene", "validate", str(_scene(folder, "part.obj"))]
        document, buffer = _box_gltf()
        (folder / document["buffers"][0]["uri"]).write_bytes(buffer)
        document["nodes"] = [{"mesh": 0, "translation": [0, 0, i * 1e-5]} for i in range(min(n, 5000))]
        document["scenes"] = [{"nodes": list(range(len(document["nodes"])))}]
        (folder / "part.gltf").write_text(json.dumps(document))
        return ["scene", "validate", str(_scene(folder, "part.gltf"))]
    # texture_picture: a texture that is a bomb, not a picture, or cut
    (folder / "part.obj").write_text("mtllib part.mtl\nusemtl m\nvt 0 0\n" + BOX_OBJ)
    (folder / "part.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd tex.png\n")
    picture = rng.choice([png(20_000, 20_000), png(4097, 2), png(0, 0), png(8, 8, 8)[:30], b"GIF89a" + b"\xff" * 9,
                          b"BM" + struct.pack("<IHHIIii", 99, 0, 0, 54, 40, 200_000, 200_000) + bytes(20)])
    (folder / "tex.png").write_bytes(picture)
    return ["scene", "validate", str(_scene(folder, "part.obj"))]


# ---------------------------------------------------------------- URDF trees
def make_urdf(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    (folder / "box.obj").write_text(BOX_OBJ)
    visual = '<visual><geometry><mesh filename="box.obj"/></geometry></visual>'
    if kind in ("chain", "links"):
        n = rng.choice([2, 50, 1200, 3000]) if kind == "chain" else rng.choice([10_001, 30_000])
        order = list(range(n - 1, -1, -1)) if rng.random() < 0.7 else list(range(n))
        links = [f'<link name="l{i}">{visual if i == n - 1 else ""}</link>' for i in order]
        joints = [f'<joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{i + 1}"/></joint>'
                  for i in order[:-1] if i + 1 < n]
        if rng.random() < 0.3:  # a loop
            joints.append(f'<joint name="back" type="fixed"><parent link="l{n - 1}"/><child link="l0"/></joint>')
        text = f'<robot name="r">{"".join(links)}{"".join(joints)}</robot>'
    elif kind == "numbers":
        value = rng.choice(["nan", "inf", "1e400", "-0", "1e-400", "x", "1 2", "1,2,3,4", "9" * 5000])
        text = (f'<robot name="r"><link name="a"><inertial><mass value="{value}"/></inertial>'
                f'<visual><origin xyz="{value} 0 0" rpy="0 {value} 0"/><geometry><mesh filename="box.obj" '
                f'scale="{value} 1 1"/></geometry><material name="m"><color rgba="{value} 0 0 1"/></material>'
                "</visual></link></robot>")
    elif kind == "xml":
        text = rng.choice([
            '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;">]>'
            '<robot name="&b;"/>',
            f'<!DOCTYPE r [<!ENTITY x SYSTEM "file://{trap["secret"]}">]><robot name="&x;"/>',
            "<robot>" + "<link>" * 20_000 + "</link>" * 20_000 + "</robot>",
            f'<robot name="r"><link name="{"n" * 1_000_000}">{visual}</link></robot>',
            "<robot", "\x00\xff\xfe", "<notrobot/>"])
    else:  # mesh_names
        # a URDF may name meshes anywhere, links followed (the user's own file, docs/security.md): never the trap
        name = rng.choice([_hostile_name(rng, trap, folder), "/dev/zero", "package://../../etc",
                           "package://x/" + "../" * 4 + "etc/passwd", "file:///dev/zero", str(trap["fifo"])])
        if trap["secret"].name in name or name in ("link.png", "ok.png"):
            name = "/dev/zero"
        text = f'<robot name="r"><link name="a"><visual><geometry><mesh filename="{name}"/></geometry></visual>' \
               "</link></robot>"
    (folder / "part.urdf").write_text(text)
    return ["scene", "validate", str(_scene(folder, "part.urdf", shape="urdf"))]


# ---------------------------------------------------------------- collision-cache entries
def make_cache(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    """A hostile entry (or folder) where the box's collision shapes are cached; the worker asks for them."""
    import numpy as np

    spec: dict[str, Any] = {"kind": kind}
    if kind == "folder":
        spec["folder"] = rng.choice(["world_writable", "symlink", "file"])
        return ["@cache", str(folder), json.dumps(spec)]
    hull = np.array([[x, y, z] for x in (-0.02, 0.02) for y in (-0.02, 0.02) for z in (-0.02, 0.02)], float)
    arrays: dict[str, Any] = {"part_0": hull, "count": np.asarray(1), "source": np.asarray("convex hull"),
                              "volume_m3": np.asarray(6.4e-5)}
    if kind == "volume":
        arrays["volume_m3"] = np.asarray(rng.choice([0.0, -1.0, float("nan"), float("inf"), 1e30, 1e-300]))
    elif kind == "parts":
        roll = rng.randrange(5)
        if roll == 0:
            arrays.update({f"part_{i}": hull for i in range(rng.choice([2000, 100_000]))})
            arrays["count"] = np.asarray(len(arrays) - 3)
        elif roll == 1:
            arrays["part_0"] = hull + rng.choice([1000.0, float("nan"), 1e308])
        elif roll == 2:
            arrays["part_0"] = hull[:3]
        elif roll == 3:
            arrays["count"] = np.asarray(rng.choice([10**9, -1, 0, 2]))
        else:
            arrays["part_0"] = np.zeros((2, 2, 2))
    spec["arrays"] = True
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, **arrays)
    data = buffer.getvalue()
    if kind == "archive":
        roll = rng.randrange(4)
        if roll == 0:
            data = data[: rng.randrange(len(data))]
        elif roll == 1:
            data = _flip(data, rng, rng.randint(1, 30))
        elif roll == 2:
            spec["entry"] = "fifo"
        else:
            spec["entry"] = "bomb"
    (folder / "entry.npz").write_bytes(data)
    return ["@cache", str(folder), json.dumps(spec)]


def run_cache(folder: str, spec_text: str) -> tuple[int, str]:
    """Ask for the box's collision shapes with the hostile entry (or folder) in place: exit 0 when shapes come
    back right (a hostile entry computed again), exit 2 with the InputError's sentence (a folder someone else
    controls); a hostile entry used is a failure."""
    import numpy as np

    from bt_grasp.errors import InputError
    from bt_grasp.scene import mesh_cache
    from bt_grasp.scene.format import load_scene

    spec = json.loads(spec_text)
    case = Path(folder)
    geometry = load_scene(REPO / "tests/data/meshes/scene_box_mesh.yaml").objects[0].geometry
    cache = case / "cache"
    if spec.get("folder") == "symlink":
        (case / "real").mkdir(mode=0o700)
        cache.symlink_to(case / "real")
    elif spec.get("folder") == "file":
        cache.write_text("")
    else:
        cache.mkdir(mode=0o700)
        if spec.get("folder") == "world_writable":
            cache.chmod(0o777)
    if spec.get("arrays") or spec.get("entry"):
        entry = cache / f"{mesh_cache.cache_key(geometry, mesh_cache.CoacdParams())}.npz"
        if spec.get("entry") == "fifo":
            os.mkfifo(entry)
        elif spec.get("entry") == "bomb":
            import zipfile

            with zipfile.ZipFile(entry, "w", zipfile.ZIP_DEFLATED) as z, z.open("part_0.npy", "w",
                                                                                force_zip64=True) as f:
                for _ in range(4):  # 256 MB of zeros in about 250 KB: past the 64 MB an entry's members may hold
                    f.write(bytes(64 << 20))
        else:
            os.replace(case / "entry.npz", entry)
    try:
        shapes = mesh_cache.collision_shapes(geometry, folder=cache)
    except InputError as exc:
        return 2, f"bt-grasp: error: {exc}\n"
    lo, hi = np.asarray(geometry.bounds_m[0]), np.asarray(geometry.bounds_m[1])
    good = (np.isfinite(shapes.volume_m3) and 0 < shapes.volume_m3 < 1e-3 and shapes.parts
            and all(np.all(p.min(axis=0) >= lo - 0.01) and np.all(p.max(axis=0) <= hi + 0.01) for p in shapes.parts))
    if not good:
        return -1, f"Traceback: a hostile cache entry was used (volume {shapes.volume_m3!r}, {len(shapes.parts)} parts)"
    return 0, ""


# ---------------------------------------------------------------- ONNX models
def make_model(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    import numpy as np
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    path = folder / "model.onnx"
    names = {0: "mug"}
    if kind == "special_file":
        if rng.random() < 0.5:
            os.mkfifo(path)
            return ["detector", "check", str(path)]
        return ["detector", "check", "/dev/zero"]
    image = helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, 320, 320])
    out = helper.make_tensor_value_info("output0", TensorProto.FLOAT, [1, 6, "anchors"])
    if kind == "shape_bomb":
        n = rng.choice([275_000_000, 2**40, 16, 11_000_000])
        nodes = [helper.make_node("Constant", [], ["shape"],
                                  value=numpy_helper.from_array(np.array([1, 6, n], np.int64))),
                 helper.make_node("ConstantOfShape", ["shape"], ["output0"])]
        if rng.random() < 0.5:  # the shape from the picture's values: no inference can bound it
            nodes = [helper.make_node("ReduceMax", ["images"], ["peak"], keepdims=0),
                     helper.make_node("Cast", ["peak"], ["n"], to=TensorProto.INT64),
                     helper.make_node("Constant", [], ["axis"], value=numpy_helper.from_array(np.array([0], np.int64))),
                     helper.make_node("Unsqueeze", ["n", "axis"], ["n1"]),
                     helper.make_node("Constant", [], ["head"],
                                      value=numpy_helper.from_array(np.array([1, 6], np.int64))),
                     helper.make_node("Concat", ["head", "n1"], ["shape"], axis=0),
                     helper.make_node("ConstantOfShape", ["shape"], ["output0"])]
    else:
        table = np.zeros((1, 6, 16), np.float32)
        nodes = [helper.make_node("ReduceMax", ["images"], ["peak"], keepdims=0),
                 helper.make_node("Constant", [], ["zero"], value=numpy_helper.from_array(np.array(0.0, np.float32))),
                 helper.make_node("Mul", ["peak", "zero"], ["nothing"]),
                 helper.make_node("Constant", [], ["table"], value=numpy_helper.from_array(table)),
                 helper.make_node("Add", ["table", "nothing"], ["output0"])]
    graph = helper.make_graph(nodes, "g", [image], [out])
    if kind == "external_data":
        weight = numpy_helper.from_array(np.zeros((1, 6, 16), np.float32), name="w")
        weight.data_location = TensorProto.EXTERNAL
        del weight.external_data[:]
        for key, value in (("location", rng.choice([str(trap["secret"]), "../" * 5 + "etc/passwd", "w.bin"])),
                           ("length", str(rng.choice([384, 10**12])))):
            entry = weight.external_data.add()
            entry.key, entry.value = key, value
        weight.ClearField("raw_data")
        graph.initializer.append(weight)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 9
    if kind == "metadata":
        value = rng.choice(["{0: 'a\x1b[2J', 1: '[/]'}", "{" + "0: 'x', " * 3 + "}", "[" * 5000, "9" * 5000,
                            "{0: '" + "n" * 100_000 + "'}", "__import__('os')", "{-1: 'a'}", "[]"])
        names_text = value
        helper.set_model_props(model, {"names": names_text, "imgsz": rng.choice(["320", "[320, 320]", "1e9", "x"])})
    else:
        helper.set_model_props(model, {"names": str(names)})
    data = model.SerializeToString()
    if kind == "protobuf_bytes":
        data = _flip(data, rng, rng.randint(1, 12)) if rng.random() < 0.6 else data[: rng.randrange(len(data))]
    path.write_bytes(data)
    del onnx  # imported for its helper modules
    return ["detector", "check", str(path)]


# ---------------------------------------------------------------- control messages
def make_control(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    """Messages and parameter maps a viewer sends, written to a JSON file the worker plays."""
    allowed = folder / "allowed"
    allowed.mkdir()
    (allowed / "cal.yaml").write_text("version: 1\n")
    hostile_values: list[Any] = ["NaN", "Infinity", 1e308, -1e308, 10**30, "x" * 100_000, [], {}, None, True,
                                 "[/]\x1b[2J", str(trap["secret"]), "../" * 8 + "etc/passwd"]
    messages: list[Any] = []
    for _ in range(rng.randint(1, 6)):
        if kind == "command_json":
            command = rng.choice([
                {"kind": "set_blackboard", "key": rng.choice(["lift_height", "color", "x" * 5000]),
                 "value": rng.choice(hostile_values)},
                {"kind": "step", "n": rng.choice([0, -1, 10**12, 1.5, "2", 10**7])},
                {"kind": "fire_fault", "fault": "frame_drop",
                 "params": rng.choice([{"frames": 1e400}, [1], "x", {"a": {"b": {"c": {"d": [[[]]]}}}}])},
                {"kind": "choose_object", "choice": rng.choice([10**40, -1, "", "x" * 10_000])},
                {"kind": rng.choice(["restart", "stop", "pause", "resume", "jump", "", None])},
                {"kind": "set_breakpoints", "breakpoints": [f"tick:{i}" for i in range(rng.choice([5, 101, 20_000]))]},
            ])
            text = json.dumps(command, allow_nan=True).replace('"NaN"', "NaN").replace('"Infinity"', "Infinity")
            if rng.random() < 0.2:
                text = rng.choice(["[" * 100_000, text[: rng.randrange(len(text) + 1)], "\xff\xfe", "9" * 5000])
            messages.append({"message": text})
        elif kind == "parameters":
            name = rng.choice(["bb.lift_height", "bb.color", "run.step", "run.paused", "fault.fire", "choose.object",
                               "run.tick", "bb." + "k" * 5000, "nothing"])
            value = rng.choice([*hostile_values[2:], float("nan"), float("inf")])
            messages.append({"parameters": {name: value}})
        elif kind == "files":
            value = rng.choice([str(trap["secret"]), str(trap["fifo"]), str(allowed / "cal.yaml"),
                                str(allowed / ".." / "x"), "relative.yaml", str(allowed)])
            if rng.random() < 0.5:
                messages.append({"parameters": {"bb.calibration_file": value}})
            else:
                messages.append({"message": json.dumps({"kind": "set_blackboard", "key": "calibration_file",
                                                        "value": value})})
        else:
            specs = [rng.choice(["fail", "tick:3", "node:Lift", "bb:color", "time:1.5", "tick:-1", "time:nan",
                                 "x" * 600, "node:" + "n" * 400]) for _ in range(rng.choice([0, 3, 100, 101, 20_000]))]
            messages.append({"parameters": {"breakpoints": specs}})
    (folder / "control.json").write_text(json.dumps({"allowed": str(allowed), "messages": messages}, allow_nan=True))
    return ["@control", str(folder / "control.json")]


_CONTROL_TREE: Any = None


def run_control(case_file: str) -> tuple[int, str]:
    """Play the messages at a real tree's controller (trees/pick.xml, no simulator) through the Foxglove front end,
    then apply them at a tick boundary: every refusal one line that quotes no trap file's content, nothing sent
    with a refusal, and what the controller holds afterwards bounded and finite."""
    import math

    from bt_grasp.behaviours.library import robot_registry
    from bt_grasp.clock import ManualClock
    from bt_grasp.control import Controller, SetBlackboard, Source, Stop
    from bt_grasp.foxglove.control import FoxgloveControl
    from bt_grasp.tree.loader import load_tree

    case = json.loads(Path(case_file).read_text())
    clock = ManualClock()
    tree = load_tree(REPO / "trees/pick.xml", robot_registry(), clock=clock)
    tree.root_blackboard.set("calibration_file", "scenes/tabletop.calibration.yaml")
    controller = Controller(idle=lambda _state: controller.send(Stop(), Source.API))  # a paused run ends
    controller.attach(tree, clock.now_ns)
    controller.between_ticks(0)
    fox = FoxgloveControl(controller, control_files=Path(case["allowed"]))
    problems: list[str] = []
    for item in case["messages"]:
        if "message" in item:
            answer = fox.command_message(item["message"].encode("utf-8", "surrogatepass"))
        else:
            answer = fox.set_parameters(item["parameters"])
        if answer.problems and len(answer.problems) > len(item.get("parameters", {"m": 0})):
            return -1, f"Traceback: {len(answer.problems)} refusals for one request"
        for command in answer.sent:
            if isinstance(command, SetBlackboard) and command.key == "calibration_file":
                real, allowed = os.path.realpath(str(command.value)), os.path.realpath(case["allowed"])
                if real != allowed and not real.startswith(allowed + os.sep):
                    return -1, f"Traceback: a file outside --control-files was sent: {command.value!r}"
        problems += answer.problems
    controller.between_ticks(1)
    state = controller.state()
    if len(state.breakpoints) > 100:
        return -1, f"Traceback: the controller holds {len(state.breakpoints)} breakpoints"
    for key, value in tree.root_blackboard.items().items():
        if isinstance(value, float) and not math.isfinite(value):
            return -1, f"Traceback: blackboard entry {key} holds {value}"
    for problem in problems:
        if "\n" in problem or len(problem) > 2000:
            return -1, f"Traceback: a refusal of {len(problem)} characters or lines: {problem[:200]!r}"
    return 0, ""


# ---------------------------------------------------------------- resident requests
def make_resident(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    frames: list[dict[str, Any]] = []
    for _ in range(rng.randint(1, 4)):
        if kind == "frames":
            frames.append({"raw": base64.b64encode(rng.choice([
                b"", rng.randbytes(rng.randint(1, 64)), struct.pack("!i", -1) + struct.pack("!Q", 1 << 40),
                struct.pack("!i", 100), b"\x80\x04garbage"])).decode(), "handshake": rng.random() < 0.5,
                "key": rng.choice(["right", "wrong"])})
        else:
            request: Any = rng.choice([
                {"tree": 5}, {"tree": "x" * 100_000}, {"tree": str(trap["fifo"]), "scene": str(trap["fifo"])},
                {"tree": str(REPO / "trees/pick.xml"), "scene": str(trap["fifo"]), "seed": 0},
                {"tree": str(REPO / "trees/pick.xml"), "scene": str(trap["fifo"]), "seed": "x",
                 "max_ticks": 10**30}, None, [1, 2], "[" * 5000])
            message: dict[str, Any] = {"v": rng.choice([1, 1, 1, 99, "1"]), "kind": rng.choice(
                ["run", "run", "ping", "jump", ""]), "request": request, "code_version": rng.choice(["current", "old"])}
            frames.append({"message": message})
    (folder / "resident.json").write_text(json.dumps(frames))
    return ["@resident", str(folder / "resident.json")]


def run_resident(case_file: str) -> tuple[int, str]:
    """Send the frames to this worker's resident (started on first use, in a private folder of the job's), each on
    its own connection; then the resident must still answer a ping within a few seconds."""
    from multiprocessing.connection import Client

    from bt_grasp.resident.client import resident_status
    from bt_grasp.resident.protocol import authkey, code_version, socket_path
    from bt_grasp.resident.wire import WireError, client_handshake, receive, send

    _ensure_resident()
    stale = False  # a request for other code: the resident answers "stale" and leaves by design
    for frame in json.loads(Path(case_file).read_text()):
        with contextlib.suppress(OSError, EOFError, WireError), Client(str(socket_path()), family="AF_UNIX") as conn:
            if "raw" in frame:
                if frame["handshake"]:
                    client_handshake(conn, authkey() if frame["key"] == "right" else b"w" * 32, 5)
                conn._send(base64.b64decode(frame["raw"]))  # type: ignore[attr-defined]
                conn.poll(0.2)
                continue
            client_handshake(conn, authkey(), 5)
            message = dict(frame["message"])
            message["code_version"] = code_version() if message.get("code_version") == "current" else "old"
            old = message["code_version"] == "old"
            stale = stale or (message.get("v") == 1 and message.get("kind") == "run" and old)
            fields = {k: v for k, v in message.items() if k not in ("v", "kind")}
            if message.get("v") == 1:
                send(conn, str(message.get("kind")), **fields)
            else:
                conn.send_bytes(json.dumps(message).encode())
            if conn.poll(8):
                with contextlib.suppress(WireError):
                    receive(conn, 1)
    if stale:
        if _RESIDENT.get("proc") is not None:
            _RESIDENT["proc"].wait(timeout=10)
        _RESIDENT.clear()
        return 0, ""
    start = time.monotonic()
    pid, _ = resident_status()
    if pid is None or time.monotonic() - start > 5:
        _RESIDENT.clear()
        return -1, "Traceback: the resident stopped answering after the case"
    return 0, ""


_RESIDENT: dict[str, Any] = {}


def _ensure_resident() -> None:
    import subprocess
    import sys

    from bt_grasp.resident.client import resident_status

    with contextlib.suppress(Exception):
        if _RESIDENT and resident_status()[0] is not None:
            return
    proc = subprocess.Popen([sys.executable, "-m", "bt_grasp.resident.server", "600"], stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    _RESIDENT["proc"] = proc
    from bt_grasp.resident.protocol import socket_path

    deadline = time.monotonic() + 60
    while not socket_path().exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)


def stop_resident() -> None:
    proc = _RESIDENT.pop("proc", None)
    if proc is not None and proc.poll() is None:
        proc.kill()
        proc.wait(timeout=30)


# ---------------------------------------------------------------- crafted --resim logs
def make_resim(kind: str, rng: random.Random, folder: Path, trap: dict[str, Path]) -> list[str]:
    """A log whose attachments (tree, scene, a mesh and the files it names) or interventions are hostile."""
    from bt_grasp.recording.writer import RunRecorder

    scene = (REPO / "scenes/tabletop.yaml").read_text().replace("calibration: tabletop.calibration.yaml\n", "")
    mesh_name = "../tree/part.obj"
    attachments: dict[str, bytes] = {"tree/t.xml": SHORT_TREE.encode()}
    mtl = "newmtl m\nKd 0.2 0.2 0.8\n"
    obj = "mtllib part.mtl\nusemtl m\nvt 0 0\nvt 1 0\nvt 1 1\n" + BOX_OBJ
    metadata = {"seed": "0", "tree_file": "t.xml", "max_ticks": "3"}
    interventions: list[dict[str, Any]] = []
    if kind == "outside_names":
        roll = rng.randrange(3)
        if roll == 0:
            mtl += f"map_Kd {rng.choice([str(trap['secret']), str(trap['fifo']), '../../../secret.png'])}\n"
        elif roll == 1:
            mesh_name = rng.choice([str(trap["secret"]), "../../" + trap["secret"].name, str(trap["fifo"])])
        else:
            obj = obj.replace("mtllib part.mtl", f"mtllib {rng.choice([str(trap['secret']), '../../x.mtl'])}")
    elif kind == "texture_bomb":
        attachments["tree/t.png"] = rng.choice([png(20_000, 20_000), png(5000, 5), b"not a picture"])
        mtl += "map_Kd t.png\n"
    elif kind == "attachment_names":
        attachments[rng.choice(["tree/../../escaped.xml", "/abs.yaml", "scene/\x00x", "tree/" + "a/" * 40 + "x",
                                "tree/" + "n" * 300])] = b"<owned/>"
    elif kind == "interventions":
        command = rng.choice([{"kind": "set_blackboard", "key": "lift_height", "value": float("nan")},
                              {"kind": "set_blackboard", "key": "x" * 5000, "value": 1},
                              {"kind": "step", "n": 10**30}, {"kind": "jump"},
                              {"kind": "fire_fault", "fault": "frame_drop", "params": {"a": [[[[[[1]]]]]]}}])
        interventions.append({"tick": rng.choice([0, 1, -1, 10**20]), "stamp_ns": 0, "source": "foxglove",
                              "kind": str(command.get("kind")), "command": command, "effect": ""})
    else:  # mesh_damage
        obj = _flip(obj.encode(), rng, rng.randint(1, 30)).decode("latin-1")
    scene = scene.replace("  - name: red_box\n    shape: box\n    size_m: [0.05, 0.05, 0.05]\n",
                          f"  - name: red_box\n    shape: mesh\n    mesh: {json.dumps(mesh_name)}\n")
    attachments.update({"scene/s.yaml": scene.encode(), "tree/part.obj": obj.encode("latin-1", "replace"),
                        "tree/part.mtl": mtl.encode()})
    log = folder / "case.mcap"
    with RunRecorder(log, metadata=metadata, attachments=attachments, handle_signals=False,
                     time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_log(0, "INFO", "fuzz", "hostile")
        for record in interventions:
            rec.write_intervention(0, record)
    return ["replay", str(log), "--resim"]


MAKERS = {"mesh": (MESH_KINDS, make_mesh), "urdf": (URDF_KINDS, make_urdf), "cache": (CACHE_KINDS, make_cache),
          "model": (MODEL_KINDS, make_model), "control": (CONTROL_KINDS, make_control),
          "resident": (RESIDENT_KINDS, make_resident), "resim": (RESIM_KINDS, make_resim)}
RUNNERS = {"@cache": run_cache, "@control": run_control, "@resident": run_resident}
