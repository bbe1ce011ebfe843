"""Issue 22, item 3 (input files read whole): every file a user gives is read bounded; a device, a pipe or a
file over its kind's limit is one sentence and exit 2, at once."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.files.bounded_io import read_user_file

REPO = Path(__file__).resolve().parents[1]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--faults", "/dev/zero"], "/dev/zero"),
        (["run", "trees/pick.xml", "--scene", "/dev/zero"], "/dev/zero"),
        (["tree", "validate", "/dev/zero"], "/dev/zero"),
        (["scene", "validate", "/dev/zero"], "/dev/zero"),
        (["eval", "report", "/dev/zero", "--out", "/tmp/never-written.html"], "/dev/zero"),
    ],
)
def test_item3_a_device_given_as_an_input_file_is_one_sentence_at_once(args: list[str], fragment: str) -> None:
    t0 = time.monotonic()
    proc = subprocess.run([*BT, *args], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and fragment in lines[0] and "not a regular file" in lines[0], proc.stderr[-2000:]
    assert time.monotonic() - t0 < 100  # it never read the device: the whole command is start-up only


def test_a_file_over_its_limit_is_refused_before_it_is_read(tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    big.write_bytes(b"a: 1\n" * 300)
    with pytest.raises(ConfigError, match="over the 1000-byte limit"):
        read_user_file(big, 1000, error=ConfigError)
    assert read_user_file(big, 2000) == big.read_bytes()
