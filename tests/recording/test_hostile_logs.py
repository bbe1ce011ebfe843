"""Issue 22, item 1: a log's attachment names never choose where `replay --resim` writes, and its work
folder never outlives it; item 3: decompression bombs; weak item: bad log contents (a tick of the wrong type,
a tree without structure, an image that fails to decode only when shown) are one sentence, not a traceback."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.recording.writer import RunRecorder

REPO = Path(__file__).resolve().parents[2]


def _log(path: Path, attachments: dict[str, bytes], metadata: dict[str, str] | None = None) -> Path:
    with RunRecorder(path, metadata={"seed": "0", **(metadata or {})}, attachments=attachments, handle_signals=False,
                     time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_log(0, "INFO", "test", "hostile")
    return path


def _resim(log: Path, cwd: Path, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    """``replay LOG --resim`` with a temporary folder of its own (``TMPDIR``): what it leaves there is its own,
    whatever else runs on the machine (r22h, 2026-11-28: another process's resim folder appeared in the shared
    /tmp between the two looks and failed the old check)."""
    private = tmp_path / "tmpdir"
    private.mkdir(exist_ok=True)
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--resim"],
                          capture_output=True, text=True, timeout=300, cwd=cwd,
                          env={**os.environ, "TMPDIR": str(private)})


def _resim_dirs(tmp_path: Path) -> list[str]:
    return sorted(p.name for p in (tmp_path / "tmpdir").glob("bt_grasp_resim_*"))


HOSTILE = ["tree/../../../escaped.xml", "scene/../../escaped.yaml", "calibration/../../escaped.yaml"]


@pytest.mark.parametrize("name", HOSTILE)
def test_item1_resim_attachment_names_cannot_leave_the_work_folder(name: str, tmp_path: Path) -> None:
    work = tmp_path / "cwd"
    work.mkdir()
    attachments = {"tree/pick.xml": (REPO / "trees/pick.xml").read_bytes(),
                   "scene/tabletop.yaml": (REPO / "scenes/tabletop.yaml").read_bytes(), name: b"<owned/>"}
    log = _log(tmp_path / "hostile.mcap", attachments)
    proc = _resim(log, work, tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "attachment name" in lines[0] and "Traceback" not in proc.stderr, proc.stderr
    # the work folder is tmp_path/tmpdir/bt_grasp_resim_*: each name's ../ reaches at most tmp_path
    assert [p for p in tmp_path.rglob("*escaped*") if p.is_file()] == []
    assert _resim_dirs(tmp_path) == [], "the work folder was left behind"


def _outside_scene(mesh: Path) -> bytes:
    text = (REPO / "scenes/tabletop.yaml").read_text()
    return text.replace("calibration: tabletop.calibration.yaml\n", "").replace(
        "  - name: red_box\n    shape: box\n    size_m: [0.05, 0.05, 0.05]\n",
        f"  - name: red_box\n    shape: mesh\n    mesh: {mesh}\n").encode()


@pytest.mark.parametrize("what", ["scene_mesh", "tree_include"])
def test_item1_resim_reads_no_file_outside_the_logs_own(what: str, tmp_path: Path) -> None:
    """Found by the pre-review attack: attachment names were gated, but what the attached files name was not: a
    log's scene naming `/home/me/part.obj` (or a tree including `/home/me/x.xml`) made `replay --resim` read the
    user's file and carry it into the new log. Within a re-simulation every input file must lie in its folder."""
    outside = tmp_path / "private"
    outside.mkdir()
    (outside / "part.obj").write_bytes((REPO / "tests/data/meshes/box.obj").read_bytes())
    (outside / "lib.xml").write_text('<root BTCPP_format="4"><BehaviorTree ID="Lib"><AlwaysSuccess/></BehaviorTree>'
                                     "</root>")
    tree = (REPO / "trees/pick.xml").read_bytes()
    scene = (REPO / "scenes/tabletop.yaml").read_bytes()
    if what == "scene_mesh":
        scene = _outside_scene(outside / "part.obj")
    else:
        tree = tree.replace(b'main_tree_to_execute="Pick">', f'main_tree_to_execute="Pick"><include path="{outside}'
                            f'/lib.xml"/>'.encode(), 1)
    attachments = {"tree/pick.xml": tree, "scene/tabletop.yaml": scene,
                   "calibration/c.yaml": (REPO / "scenes/tabletop.calibration.yaml").read_bytes()}
    log = _log(tmp_path / "outside.mcap", attachments)
    proc = _resim(log, tmp_path, tmp_path)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "lies outside" in lines[0] and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert ("part.obj" if what == "scene_mesh" else "lib.xml") in lines[0]
    assert _resim_dirs(tmp_path) == []


@pytest.mark.parametrize(("metadata", "fragment"), [
    ({"seed": "abc"}, "'seed' is 'abc'"),
    ({"seed": "-1"}, "'seed' is '-1'"),
    ({"max_ticks": "1" + "0" * 15}, "'max_ticks' is '1000000000000000'"),
    ({"max_ticks": "0"}, "'max_ticks' is '0'"),
    ({"blackboard": "[" * 50_000}, "'blackboard' is not a JSON object"),
    ({"blackboard": '{"k": [1, 2]}'}, "'blackboard' is not a JSON object"),
])
def test_item1_resim_refuses_run_metadata_it_cannot_run(metadata: dict[str, str], fragment: str,
                                                        tmp_path: Path) -> None:
    """Found by the pre-review attack: a recorded seed or tick limit that is not an integer was a ValueError
    traceback, a blackboard nested 50,000 deep a RecursionError, and a limit of 10^15 ticks ran for ever."""
    attachments = {"tree/pick.xml": (REPO / "trees/pick.xml").read_bytes(),
                   "scene/tabletop.yaml": (REPO / "scenes/tabletop.yaml").read_bytes()}
    log = _log(tmp_path / "meta.mcap", attachments, metadata)
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--resim"],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr, proc.stderr[-2000:]


def _bomb(path: Path, declared: int, payload_bytes: int, compression: str = "zstd") -> Path:
    """An unfinished MCAP file (header, one chunk) whose chunk declares ``declared`` bytes uncompressed but
    whose frame really holds ``payload_bytes`` of zeros (its own frame header states that size)."""
    import zlib

    import lz4.frame
    import mcap.records as records
    import zstandard
    from mcap.data_stream import RecordBuilder

    zeros = bytes(payload_bytes)
    data = zstandard.ZstdCompressor().compress(zeros) if compression == "zstd" else lz4.frame.compress(zeros)
    builder = RecordBuilder()
    records.Header(profile="", library="hostile").write(builder)
    records.Chunk(compression=compression, data=data, message_start_time=0, message_end_time=0,
                  uncompressed_crc=zlib.crc32(zeros), uncompressed_size=declared).write(builder)
    path.write_bytes(b"\x89MCAP0\r\n" + builder.end())
    return path


@pytest.mark.parametrize(("declared", "payload", "compression"), [
    (100, 80 << 20, "zstd"),  # the frame states 80 MB: the old reader ignored its output limit
    (80 << 20, 80 << 20, "zstd"),  # honest about a size past the per-chunk limit
    (100, 80 << 20, "lz4"),
])
def test_item3_a_decompression_bomb_is_refused_in_one_sentence(
    declared: int, payload: int, compression: str, tmp_path: Path
) -> None:
    log = _bomb(tmp_path / "bomb.mcap", declared, payload, compression)
    assert log.stat().st_size < 1 << 20
    script = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1 << 31, 1 << 31))\n"
        "from bt_grasp.cli.main import main\n"
        f"sys.exit(main(['replay', {str(log)!r}]))\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "bomb.mcap" in lines[0] and "refused" in lines[0], proc.stderr[-2000:]


# -- issue 22, weak item: bad log *contents* (well-formed MCAP, wrong messages) are one sentence, not a traceback

SEED_LOG = REPO / "tests" / "data" / "old_logs" / "format1.mcap"


def _rewrite(path: Path, change: Any = None, metadata: dict[str, str] | None = None,
             encoding: dict[str, str] | None = None, chunk_size: int = 1 << 20) -> Path:
    """The seed log written again with the mcap library (well-formed MCAP), ``change(topic, index, data)``
    replacing message bytes, ``metadata`` overriding run metadata, ``encoding`` a topic's message encoding."""
    import io

    from mcap.reader import make_reader
    from mcap.writer import Writer

    reader = make_reader(io.BytesIO(SEED_LOG.read_bytes()))
    out = path.open("wb")
    writer = Writer(out, chunk_size=chunk_size)
    writer.start(profile="", library="test")
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    seen: dict[str, int] = {}
    for schema, channel, message in reader.iter_messages():
        if schema is not None and schema.id not in schema_ids:
            schema_ids[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channel_ids:
            enc = (encoding or {}).get(channel.topic, channel.message_encoding)
            channel_ids[channel.id] = writer.register_channel(channel.topic, enc, schema_ids.get(channel.schema_id, 0))
        index = seen[channel.topic] = seen.get(channel.topic, -1) + 1
        data = change(channel.topic, index, message.data) if change is not None else message.data
        writer.add_message(channel_ids[channel.id], message.log_time, data, message.publish_time)
    for record in reader.iter_metadata():
        writer.add_metadata(record.name, {**record.metadata, **(metadata or {})})
    writer.finish()
    out.close()
    return path


def _json_change(topic: str, index: int, edit: Any) -> Any:
    def change(t: str, i: int, data: bytes) -> bytes:
        if (t, i) != (topic, index):
            return data
        result = edit(json.loads(data))
        return result if isinstance(result, bytes) else json.dumps(result).encode()

    return change


def _replay(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str]]:
    from bt_grasp.cli.main import main

    code = main(["replay", *args])
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return code, [line for line in err.splitlines() if line.strip()]


BAD_CONTENTS = {
    "tick_is_a_string": (topics_tick := "/bt/tick", 2, lambda m: {**m, "tick": "5"}, "'tick' is a string"),
    "nodes_not_a_list": (topics_tick, 0, lambda m: {**m, "nodes": {"uid": 1}}, "'nodes' is an object"),
    "node_without_uid": (topics_tick, 1, lambda m: {**m, "nodes": [{"status": "OK"}]}, "'nodes[0].uid' is missing"),
    "tick_not_an_object": (topics_tick, 3, lambda m: [m], "is a list, not a JSON object"),
    "tree_without_structure": ("/bt/tree", 0, lambda m: {"tick": None}, "'structure' is missing"),
    "tree_structure_null": ("/bt/tree", 0, lambda m: {**m, "structure": None}, "structure is null"),
    "tree_too_deep": ("/bt/tree", 0, lambda m: {**m, "structure": _deep(150)}, "nested deeper than 100"),
    "tree_attributes_a_list": ("/bt/tree", 0, lambda m: {**m, "structure": {**m["structure"], "attributes": [1]}},
                               "'structure.attributes' is a list"),
    "joint_positions_text": ("/robot/joint_state", 4, lambda m: {**m, "position": "x"}, "'position' is a string"),
    "result_success_text": ("/run/result", 0, lambda m: {**m, "success": "yes"}, "'success' is a string"),
    "fault_stamp_text": ("/faults", 0, lambda m: {**m, "stamp_ns": "late"}, "'stamp_ns' is a string"),
    "not_utf8": (topics_tick, 2, lambda m: json.dumps(m).replace('"', '"\xe9', 1).encode("latin-1"), "not UTF-8"),
    "lone_surrogate": (topics_tick, 2, lambda m: json.dumps({**m, "bb": {"k": "\udcff"}}).encode(), "not valid"),
    "deep_json": (topics_tick, 2, lambda m: b"[" * 50_000 + b"]" * 50_000, "nested too deeply"),
}


def _deep(n: int) -> dict[str, Any]:
    node: dict[str, Any] = {"uid": 1000}
    for i in range(n):
        node = {"uid": i, "name": "d", "children": [node]}
    return node


@pytest.mark.parametrize("view", [[], ["--tick", "5"], ["--json"]])
@pytest.mark.parametrize("name", sorted(BAD_CONTENTS))
def test_weak_item_bad_message_contents_are_one_sentence_naming_file_topic_and_time(
    name: str, view: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    topic, index, edit, problem = BAD_CONTENTS[name]
    log = _rewrite(tmp_path / "bad.mcap", _json_change(topic, index, edit))
    code, lines = _replay(capsys, str(log), *view)
    if topic == "/robot/joint_state" and view != ["--tick", "5"]:  # one per tick: checked when one is shown
        assert code == 0, lines
        return
    assert code == 2 and len(lines) == 1, lines
    assert "bad.mcap" in lines[0] and f"on {topic} at " in lines[0] and problem in lines[0], lines


def test_weak_item_a_bt_grasp_topic_in_another_encoding_is_refused(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    log = _rewrite(tmp_path / "cbor.mcap", encoding={"/bt/tick": "cbor"})
    code, lines = _replay(capsys, str(log))
    assert code == 2 and len(lines) == 1 and "on /bt/tick" in lines[0] and "'cbor', not 'json'" in lines[0], lines
    log = _rewrite(tmp_path / "tfjson.mcap", encoding={"/tf": "json"})
    code, lines = _replay(capsys, str(log), "--report", str(tmp_path / "r.html"))
    assert code == 2 and len(lines) == 1 and "on /tf" in lines[0] and "not 'protobuf'" in lines[0], lines


@pytest.mark.parametrize("value", ["x", "1e400", "9" * 400, "-5"])
def test_weak_item_a_bad_time_origin_is_refused(value: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _rewrite(tmp_path / "origin.mcap", metadata={"time_origin_ns": value})
    code, lines = _replay(capsys, str(log), "--json")
    assert code == 2 and len(lines) == 1 and "'time_origin_ns'" in lines[0] and "origin.mcap" in lines[0], lines


def _image_change(topic: str, edit: Any) -> Any:
    from bt_grasp.recording.schemas import PROTOBUF_CLASSES

    def change(t: str, i: int, data: bytes) -> bytes:
        if (t, i) != (topic, 1):
            return data
        msg = PROTOBUF_CLASSES["foxglove.CompressedImage" if t == "/camera/color" else "foxglove.RawImage"]()
        msg.ParseFromString(data)
        edit(msg)
        return bytes(msg.SerializeToString())

    return change


def _png_header(width: int, height: int) -> bytes:
    import struct
    import zlib

    ihdr = b"IHDR" + struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + ihdr + struct.pack(">I", zlib.crc32(ihdr))


IMAGES = {
    "colour_not_an_image": ("/camera/color", lambda m: setattr(m, "data", b"\x89PNG not really"),
                            "is not a PNG or JPEG"),
    "colour_header_only": ("/camera/color", lambda m: setattr(m, "data", _png_header(10, 10)), "does not decode"),
    # found by the pre-review attack: a 2.6 MB PNG of zeros saying 30,000 x 30,000 took 5-8 GB and 90 s to decode
    "colour_decompression_bomb": ("/camera/color", lambda m: setattr(m, "data", _png_header(30_000, 30_000)),
                                  "30000 x 30000 pixels, more than a camera's 4096 a side"),
    "depth_short": ("/camera/depth", lambda m: setattr(m, "data", m.data[:-7]), "are not"),
    "depth_encoding": ("/camera/depth", lambda m: setattr(m, "encoding", "rgb8"), "'rgb8' is not one of"),
    "depth_no_rows": ("/camera/depth", lambda m: setattr(m, "height", 0), "are not 0 rows"),
}


@pytest.mark.parametrize("view", ["--export-frames", "--report"])
@pytest.mark.parametrize("name", sorted(IMAGES))
def test_weak_item_an_image_that_fails_to_decode_only_when_shown_is_one_sentence(
    name: str, view: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    topic, edit, problem = IMAGES[name]
    log = _rewrite(tmp_path / "img.mcap", _image_change(topic, edit))
    code, lines = _replay(capsys, str(log), view, str(tmp_path / ("frames" if view == "--export-frames" else "r.html")))
    assert code == 2 and len(lines) == 1, lines
    assert "img.mcap" in lines[0] and f"bad image on {topic} at " in lines[0] and problem in lines[0], lines
    code, lines = _replay(capsys, str(log), "--json")  # the summary does not read images: the log opens
    assert code == 0, lines


def test_weak_item_damage_only_where_the_index_points_for_images_is_one_sentence(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The eager read skips image chunks; the chunk of the second colour image is damaged, so the file opens
    through its index and the damage is found only when the frames are exported."""
    import io

    from mcap.reader import make_reader

    log = _rewrite(tmp_path / "idx.mcap", chunk_size=64)  # about one message per chunk
    data = bytearray(log.read_bytes())
    summary = make_reader(io.BytesIO(bytes(data))).get_summary()
    assert summary is not None
    color = next(c.id for c in summary.channels.values() if c.topic == "/camera/color")
    image_chunks = [c for c in summary.chunk_indexes if set(c.message_index_offsets) == {color}]
    chunk = image_chunks[1]
    name_at = chunk.chunk_start_offset + 1 + 8 + 8 + 8 + 8 + 4 + 4  # opcode, length, start, end, size, crc, name length
    assert data[name_at: name_at + 4] == b"zstd"
    data[name_at: name_at + 4] = b"zstx"  # a compression nobody knows: the chunk cannot be read
    log.write_bytes(bytes(data))
    code, lines = _replay(capsys, str(log), "--json")
    assert code == 0, lines
    code, lines = _replay(capsys, str(log), "--export-frames", str(tmp_path / "frames"))
    assert code == 2 and len(lines) == 1 and "idx.mcap" in lines[0] and "/camera/color" in lines[0], lines


def test_weak_item_image_sizes_are_read_from_headers_only() -> None:
    import cv2
    import numpy as np

    from bt_grasp.files.image_header import image_size

    picture = np.zeros((48, 64, 3), np.uint8)
    for ext, params in ((".png", []), (".jpg", []), (".jpg", [cv2.IMWRITE_JPEG_PROGRESSIVE, 1])):
        ok, data = cv2.imencode(ext, picture, params)
        assert ok and image_size(data.tobytes()) == (64, 48)
    assert image_size(_png_header(30_000, 20_000)) == (30_000, 20_000)
    for junk in (b"", b"GIF89a....", b"\xff\xd8\xff", b"\xff\xd8\x00\x00", b"\x89PNG\r\n\x1a\n\x00"):
        assert image_size(junk) is None


# -- issue 42: what the files a log carries name in turn ----------------------------------------------------------
SHORT_TREE = (b'<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T"><AlwaysSuccess/>'
              b"</BehaviorTree></root>")


def _mesh_log(tmp_path: Path, texture: str, extra: dict[str, bytes] | None = None) -> Path:
    """A log whose scene draws a mesh the log carries (beside its tree), whose material names ``texture``."""
    box = (REPO / "tests/data/meshes/box.obj").read_text()
    attachments = {"tree/t.xml": SHORT_TREE, "scene/s.yaml": _outside_scene(Path("../tree/part.obj")),
                   "tree/part.obj": ("mtllib part.mtl\nusemtl m\nvt 0 0\nvt 1 0\nvt 1 1\n" + box).encode(),
                   "tree/part.mtl": f"newmtl m\nKd 0.2 0.2 0.8\nmap_Kd {texture}\n".encode(), **(extra or {})}
    return _log(tmp_path / "mesh.mcap", attachments, {"tree_file": "t.xml", "max_ticks": "3"})


@pytest.mark.parametrize("outside", ["image", "fifo", "absent"])
def test_finding1_resim_never_reads_a_texture_outside_the_log_nor_tells_whether_it_exists(
        outside: str, tmp_path: Path) -> None:
    """A crafted log carrying a mesh whose .mtl names an absolute image path outside the log made `replay
    --resim` read that image and draw it into the new log's camera frames; the 'missing texture' warning also told
    whether the outside file exists. Now the name is never opened: whatever is there (an image, a FIFO that would
    block any reader, nothing), the re-simulation says the same."""
    import struct
    import zlib

    secret = tmp_path / "private" / "secret.png"
    secret.parent.mkdir()
    if outside == "image":
        row = b"\x00" + b"\xff\x00\x00" * 4
        body = zlib.compress(row * 4)

        def chunk(kind: bytes, data: bytes) -> bytes:
            return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

        secret.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 2, 0, 0, 0))
                           + chunk(b"IDAT", body) + chunk(b"IEND", b""))
    elif outside == "fifo":
        os.mkfifo(secret)
    log = _mesh_log(tmp_path, str(secret))
    proc = _resim(log, tmp_path, tmp_path)
    assert "Traceback" not in proc.stderr and proc.returncode in (0, 1, 2), proc.stderr[-3000:]
    said = proc.stderr.replace(str(tmp_path), "TMP")
    assert "outside" in said and "missing" not in said, said
    assert _resim_dirs(tmp_path) == []


def test_finding2_resim_refuses_a_texture_bomb_the_log_carries(tmp_path: Path) -> None:
    """A 1.2 MB log carrying a 431 KB PNG that declares 20000 x 20000 took 5.3 GB in `--resim` (or a RuntimeError
    traceback under a 4 GB limit)."""
    import resource
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    bomb = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 20000, 20000, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\x00" * 60001 * 8, 9)) + chunk(b"IEND", b""))
    log = _mesh_log(tmp_path, "bomb.png", {"tree/bomb.png": bomb})
    private = tmp_path / "tmpdir"
    private.mkdir()

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))

    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--resim"],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path, preexec_fn=limited,
                          env={**os.environ, "TMPDIR": str(private)})
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert "bomb.png" in lines[0] and "20000 x 20000" in lines[0], lines[0]
    assert _resim_dirs(tmp_path) == []
