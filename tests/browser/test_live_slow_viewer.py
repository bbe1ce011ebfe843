"""A viewer that stops reading never stalls the run: the recorder keeps writing at full speed while the live
server drops what the stalled viewer cannot take (frames, not ticks)."""

from __future__ import annotations

import os
import shutil
import subprocess
import time

import numpy as np
import pytest
from studio_driver import CACHE, HERE

from bt_grasp.foxglove.live import LiveServer
from bt_grasp.recording.writer import RunRecorder


def test_a_stalled_viewer_does_not_stall_the_writer() -> None:
    if shutil.which("node") is None or not (CACHE / "node_modules" / "ws" / "package.json").is_file():
        print("SKIPPED (browser): node or the ws package is missing (tools/setup_browser.sh installs them)")
        pytest.skip("node or the ws package is missing")
    server = LiveServer(port=0, backlog=64)
    recorder = RunRecorder(None, metadata={}, handle_signals=False)
    server.attach(recorder)
    viewer = subprocess.Popen(["node", str(HERE / "stalled_viewer.cjs"), server.url], stdout=subprocess.PIPE,
                              text=True, cwd=CACHE, env={**os.environ, "NODE_PATH": str(CACHE / "node_modules")})
    try:
        assert viewer.stdout is not None
        assert viewer.stdout.readline().startswith("SUBSCRIBED")
        deadline = time.monotonic() + 30
        while not server.watched and time.monotonic() < deadline:
            time.sleep(0.05)
        assert server.watched and recorder.active
        time.sleep(0.5)  # the viewer has stopped reading
        noise = np.random.default_rng(0).integers(0, 256, (480, 640, 3), dtype=np.uint8)  # ~400 kB as JPEG
        started = time.monotonic()
        for i in range(600):  # ~240 MB: far more than any socket buffer holds
            recorder.write_color_image(i * 10_000_000, noise, "camera_color_optical_frame")
            recorder.write_tick(i + 1, i * 10_000_000, [], {}, {"q_rad": [0.0] * 6})
        elapsed = time.monotonic() - started
        assert elapsed < 60, f"writing took {elapsed:.1f} s: the stalled viewer held the run back"
        assert server.dropped_errors == 0
    finally:
        viewer.kill()
        viewer.communicate()
        recorder.close()
        server.close()
