"""Issue 22, item 1: a log's attachment names never choose where `replay --resim` writes, and its work
folder never outlives it."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from bt_grasp.recording.writer import RunRecorder

REPO = Path(__file__).resolve().parents[2]


def _log(path: Path, attachments: dict[str, bytes]) -> Path:
    with RunRecorder(path, metadata={"seed": "0"}, attachments=attachments, handle_signals=False,
                     time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_log(0, "INFO", "test", "hostile")
    return path


def _resim_dirs() -> set[str]:
    return {p.name for p in Path(tempfile.gettempdir()).glob("bt_grasp_resim_*")}


HOSTILE = ["tree/../../../escaped.xml", "scene/../../escaped.yaml", "calibration/../../escaped.yaml"]


@pytest.mark.parametrize("name", HOSTILE)
def test_item1_resim_attachment_names_cannot_leave_the_work_folder(name: str, tmp_path: Path) -> None:
    work = tmp_path / "cwd"
    work.mkdir()
    attachments = {"tree/pick.xml": (REPO / "trees/pick.xml").read_bytes(),
                   "scene/tabletop.yaml": (REPO / "scenes/tabletop.yaml").read_bytes(), name: b"<owned/>"}
    log = _log(tmp_path / "hostile.mcap", attachments)
    before = _resim_dirs()
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--resim"],
                          capture_output=True, text=True, timeout=300, cwd=work)
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "attachment name" in lines[0] and "Traceback" not in proc.stderr, proc.stderr
    escaped = [p for p in Path(tempfile.gettempdir()).rglob("*escaped*") if p.is_file()]
    escaped += [p for p in tmp_path.rglob("*escaped*") if p.is_file()]
    assert escaped == []
    assert _resim_dirs() <= before, "the work folder was left behind"


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
