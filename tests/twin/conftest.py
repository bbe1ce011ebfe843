"""One twin for the whole folder: ``bt-grasp twin`` in a process of its own, on a loopback address of its own.

ur_rtde's ports are fixed, so the address must be free of other twins (other engineers' test runs share this
machine): a free 127.x.y.z is found by binding every port first. The twin runs with ``--unlock-delay 0.5`` so a
protective-stop test does not wait a robot's 5 s (the 5 s rule itself is checked with it, in
``test_twin_ur_rtde.py``). Tests that change the twin's state put it back (program running, safety normal).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from bt_grasp.bench.twin_process import free_loopback

REPO = Path(__file__).resolve().parents[2]

#: Wall-clock bounds. Issue 40's figures (a fault seen within one period + 50 ms, the period's 99th percentile under
#: twice 8 ms) are measured with ``BT_GRASP_STRICT_TIMING=1 pytest -s tests/twin/test_twin_faults.py
#: tests/twin/test_twin_rtde_guide.py`` (docs/twin.md), where the strict bounds are asserted. In ``make test`` the
#: same tests check what is seen (the fault, its state, no cycle lost: counted by the twin's own RTDE timestamps) and
#: bound the wall time generously: on this 2-core machine shared by several test runs a client's wake-up alone was
#: measured late by 75 ms (a gripper timeout of 58 ms seen after 75 ms), which is the load, not the twin.
STRICT_TIMING = os.environ.get("BT_GRASP_STRICT_TIMING") == "1"
START_TIMEOUT_S = 90.0


def control(host: str, line: str, timeout_s: float = 30.0) -> dict[str, object]:
    """One request on the twin's control port; the JSON reply."""
    with socket.create_connection((host, 30100), timeout=timeout_s) as s:
        s.sendall(line.encode() + b"\n")
        buf = b""
        while not buf.endswith(b"\n"):
            chunk = s.recv(65536)
            if not chunk:
                break
            buf += chunk
    reply = json.loads(buf)
    assert isinstance(reply, dict)
    return reply


@dataclass
class TwinProcess:
    host: str
    process: subprocess.Popen[bytes]
    log_path: Path
    cell_path: Path

    def control(self, line: str) -> dict[str, object]:
        return control(self.host, line)

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")


def start_twin(tmp: Path, *extra: str, salt: int = 0) -> TwinProcess:
    for attempt in range(3):
        host = free_loopback(salt + attempt)
        log_path = tmp / f"twin-{host}.log"
        cell_path = tmp / "twin.cell.yaml"
        with open(log_path, "wb") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", "bt_grasp.cli.main", "twin", "--scene", "scenes/tabletop.yaml", "--host", host,
                 "--unlock-delay", "0.5", "--write-cell", str(cell_path), *extra],
                cwd=REPO, stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline and process.poll() is None:
            with contextlib.suppress(OSError, ValueError):
                if control(host, "status", timeout_s=2.0).get("ok"):
                    return TwinProcess(host, process, log_path, cell_path)
            time.sleep(0.2)
        if process.poll() is None:
            process.kill()
            process.wait()
            raise RuntimeError(f"the twin did not come up in {START_TIMEOUT_S:g} s:\n{log_path.read_text()}")
    raise RuntimeError(f"the twin exited at start:\n{log_path.read_text()}")


def stop_twin(twin: TwinProcess) -> int:
    if twin.process.poll() is None:
        twin.process.send_signal(signal.SIGTERM)
        try:
            return twin.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            twin.process.kill()
            twin.process.wait()
            return -9
    return int(twin.process.returncode)


@pytest.fixture(scope="session")
def twin(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TwinProcess]:
    pytest.importorskip("rtde_control", reason="ur_rtde is not installed (pip install -e '.[ur]')")
    started = start_twin(tmp_path_factory.mktemp("twin"))
    yield started
    code = stop_twin(started)
    assert code == 0, started.log()[-3000:]
