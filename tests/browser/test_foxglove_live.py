"""A run served live (`bt-grasp run ... --live PORT`) watched in a real Foxglove Studio through its
"Foxglove WebSocket" data source: no problem for any topic, the 3D panel knows every link and draws, the image
panel draws. The viewer joins only after the run has printed tick 100, i.e. after Perceive (tick 1) captured the
only picture while nobody watched: the latched topics must reach a viewer that joins mid-run."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from studio_driver import ROBOT_LINKS, open_in_studio, serving, skip_without_browser

from bt_grasp.foxglove.tree_layout import layout_for_tree_file
from tests.terminal_stderr import TerminalStderr

ROOT = Path(__file__).resolve().parents[2]

pytestmark = [pytest.mark.sim, pytest.mark.slow]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _wait_for_port(port: int, proc: subprocess.Popen[str], timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"the run ended before serving: {proc.communicate()}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.2)
    raise AssertionError(f"nothing listens on {port} after {timeout_s} s")


def _wait_for_line(run: TerminalStderr, prefix: str, timeout_s: float,
                   seen: list[str] | None = None) -> None:
    """Read the run's progress (stderr, a terminal: the run draws its progress on one only) until a line starts
    with ``prefix`` (a reader thread: it may stay silent); the lines read are appended to ``seen``."""
    found = threading.Event()

    def read() -> None:
        for line in run.lines():
            if seen is not None:
                seen.append(line)
            if line.startswith(prefix):
                found.set()
                return

    threading.Thread(target=read, daemon=True).start()
    if not found.wait(timeout_s):
        raise AssertionError(f"the run printed no line starting {prefix!r} within {timeout_s} s")


def test_live_run_shows_whole_in_foxglove(tmp_path: Path) -> None:
    skip_without_browser()
    port = _free_port()
    # slower than real time (at 0.03x: tick 100 after ~33 s, the pick's end after ~245 s) so the run is still
    # going while Studio starts, subscribes, draws (waited for, up to 100 s) and is looked at
    run = TerminalStderr(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(ROOT / "trees/pick.xml"),
         "--scene", str(ROOT / "scenes/tabletop.yaml"), "--live", str(port), "--realtime", "0.03",
         "--max-ticks", "1000"],
        stdout=subprocess.DEVNULL, text=True, cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1", "COLUMNS": "200",
             "TMPDIR": str(tmp_path)},  # where the run writes its layout (it has no log)
    )
    proc = run.proc
    try:
        _wait_for_port(port, proc, 120)
        said: list[str] = []
        _wait_for_line(run, "tick   100", 120, said)  # Perceive (tick 1) is over; nobody has watched yet
        # the layout the run wrote for its tree (its leaves' rows, by path), as it told the user
        told = next(line for line in said if line.startswith("live: "))
        layout = Path(told.rsplit("(layout: ", 1)[1].strip().rstrip(")"))
        assert json.loads(layout.read_text()) == layout_for_tree_file(ROOT / "trees/pick.xml")
        with serving(tmp_path, layout) as server:
            report = open_in_studio(server.url_for_websocket(), tmp_path, wait_s=5,
                                    until=("3d", "image", "state"), max_wait_s=100,
                                    screenshot=tmp_path / "live.png", ws_bridge=f"ws://127.0.0.1:{port}")
        assert proc.poll() is None, "the run ended before the viewer looked: the test proves nothing"
    finally:
        proc.kill()
        proc.wait()
        run.close()
    assert report.errors == []
    assert report.problems == [] and report.problem_count == 0, report.problems
    assert set(ROBOT_LINKS) <= set(report.frames), report.frames
    waited = {k: report.raw.get(k) for k in ("waitedS", "notDrawnAtDeadline", "shotWaitS", "notDrawnAtShots")}
    assert report.three_d_drawn, f"the 3D panel drew nothing ({waited})"
    assert report.image_drawn, f"the image panel drew nothing ({waited})"
    assert report.state_transitions_drawn, f"State Transitions drew no leaf status from /bt/tick.leaves ({waited})"
