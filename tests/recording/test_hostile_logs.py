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
