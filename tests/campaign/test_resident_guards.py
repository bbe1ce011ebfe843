"""Issue 22, items 2 and 8, and a resident killed under its client: the resident refuses folders others
control, one resident per folder by a lock, and a client whose resident dies says so."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]
RUN = ["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--resident"]


def _env(folder: Path) -> dict[str, str]:
    env = dict(os.environ, BT_GRASP_RESIDENT_DIR=str(folder))
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _one_sentence(proc: subprocess.CompletedProcess[str], *fragments: str) -> None:
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_item2_a_folder_writable_by_others_is_refused_and_nothing_starts(tmp_path: Path) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    proc = subprocess.run([*BT, *RUN], capture_output=True, text=True, timeout=120, cwd=REPO, env=_env(shared))
    _one_sentence(proc, "BT_GRASP_RESIDENT_DIR", "writable by others")
    assert list(shared.iterdir()) == [], "nothing may be created in a refused folder"


@pytest.mark.skipif(os.getuid() != 0, reason="making a folder of another user needs root")
def test_item2_a_folder_of_another_user_is_refused(tmp_path: Path) -> None:
    theirs = tmp_path / "theirs"
    theirs.mkdir(mode=0o700)
    os.chown(theirs, 65534, 65534)
    (theirs / "key").write_bytes(b"k" * 32)  # their key, and (were it accepted) their socket
    proc = subprocess.run([*BT, *RUN], capture_output=True, text=True, timeout=120, cwd=REPO, env=_env(theirs))
    _one_sentence(proc, "belongs to user id 65534")


def test_item2_a_symbolic_link_as_the_folder_is_refused(tmp_path: Path) -> None:
    real = tmp_path / "real"
    real.mkdir(mode=0o700)
    link = tmp_path / "link"
    link.symlink_to(real)
    proc = subprocess.run([*BT, *RUN], capture_output=True, text=True, timeout=120, cwd=REPO, env=_env(link))
    _one_sentence(proc, "not a plain folder")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return Path(f"/proc/{pid}/stat").read_text().split(")")[1].split()[0] != "Z"


def test_item8_two_residents_started_at_once_leave_one_serving(tmp_path: Path) -> None:
    folder = tmp_path / "resident"
    env = _env(folder)
    server = [sys.executable, "-m", "bt_grasp.resident.server", "60"]
    procs = [subprocess.Popen(server, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True) for _ in range(2)]
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and all(p.poll() is None for p in procs):
            time.sleep(0.1)
        exited = [p for p in procs if p.poll() is not None]
        assert len(exited) == 1 and exited[0].returncode == 0, "exactly one of the two must leave, quietly"
        live = next(p for p in procs if p.poll() is None)
        ping = ("from bt_grasp.resident.client import stop_resident\nimport time\n"
                "for _ in range(600):\n    pid = stop_resident()\n    if pid: print(pid); break\n    time.sleep(0.1)\n")
        out = subprocess.run([sys.executable, "-c", ping], env=env, capture_output=True, text=True, timeout=120)
        assert out.stdout.strip() == str(live.pid), out.stderr
        live.wait(timeout=30)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.wait(timeout=30)
    assert not (folder / "episode.sock").exists()
