"""A twin in a process of its own, for benchmarks (and tests) that run bt-grasp against it: started on a loopback
address whose ports are all free (ur_rtde's ports are fixed, so twins side by side need their own addresses), its
cell file written, stopped with SIGTERM (SIGKILL when it does not stop)."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_grasp.hardware.twin_control import TwinControlError, twin_request

#: every port a twin serves (RTDE, dashboard, script, gripper, control, camera)
TWIN_PORTS = (30004, 29999, 30003, 63352, 30100, 30101)
START_TIMEOUT_S = 120.0


def free_loopback(salt: int = 0) -> str:
    """A 127.x.y.z address on which every twin port is free now."""
    base = (os.getpid() * 7 + salt * 131) % 200
    for k in range(80):
        host = f"127.{61 + (base + k) % 190}.{(os.getpid() + k) % 250 + 1}.{2 + (k + salt) % 200}"
        socks: list[socket.socket] = []
        try:
            for port in TWIN_PORTS:
                s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                socks.append(s)
                s.bind((host, port))
            return host
        except OSError:
            continue
        finally:
            for s in socks:
                s.close()
    raise RuntimeError("no loopback address with the twin's ports free")


@dataclass
class TwinProcess:
    """A running ``bt-grasp twin``: its address, process, log and cell file."""

    host: str
    process: subprocess.Popen[bytes]
    log_path: Path
    cell_path: Path
    started_in_s: float

    def control(self, line: str, timeout_s: float = 30.0) -> dict[str, Any]:
        return twin_request(self.host, line, timeout_s=timeout_s)

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def stop(self) -> int:
        """SIGTERM, then SIGKILL after 20 s; the exit code (-9 when killed)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                return self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
                return -9
        return int(self.process.returncode)


def start_twin(scene: Path | str, workdir: Path, *extra: str, seed: int = 0, salt: int = 0,
               repo: Path | None = None) -> TwinProcess:
    """Start ``bt-grasp twin --scene SCENE --seed SEED --host H --write-cell WORKDIR/cell-H.yaml EXTRA...`` and wait
    until its control port answers (RuntimeError with its log when it does not come up)."""
    workdir.mkdir(parents=True, exist_ok=True)
    for attempt in range(3):
        host = free_loopback(salt + attempt)
        log_path = workdir / f"twin-{host}.log"
        cell_path = workdir / f"cell-{host}.yaml"
        with contextlib.suppress(FileNotFoundError):
            cell_path.unlink()
        started = time.monotonic()
        with open(log_path, "wb") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", "bt_grasp.cli.main", "twin", "--scene", str(scene), "--seed", str(seed),
                 "--host", host, "--write-cell", str(cell_path), *extra],
                cwd=repo, stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline and process.poll() is None:
            with contextlib.suppress(TwinControlError):
                if twin_request(host, "status", timeout_s=2.0).get("ok") and cell_path.exists():
                    return TwinProcess(host, process, log_path, cell_path, time.monotonic() - started)
            time.sleep(0.2)
        if process.poll() is None:
            process.kill()
            process.wait()
            raise RuntimeError(f"the twin did not come up in {START_TIMEOUT_S:g} s:\n{log_path.read_text()[-3000:]}")
    raise RuntimeError(f"the twin exited at start:\n{log_path.read_text()[-3000:]}")
