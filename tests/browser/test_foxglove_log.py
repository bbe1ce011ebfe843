"""A recorded pick opened in a real Foxglove Studio (the open-source web build 1.48) with the shipped layout:
no problem for any topic, the 3D panel knows every link of the robot and draws, the image panel draws."""

from __future__ import annotations

import datetime
import os
import subprocess
import sys
from pathlib import Path

import pytest
from studio_driver import ROBOT_LINKS, open_in_studio, serving, skip_without_browser

from bt_grasp.recording.reader import open_log

ROOT = Path(__file__).resolve().parents[2]
LAYOUT = ROOT / "bt_grasp" / "foxglove" / "layouts" / "bt_grasp.layout.json"

pytestmark = [pytest.mark.sim, pytest.mark.slow]


def end_time_iso(log_path: Path) -> str:
    """The log's last tick as an ISO time for Foxglove's ``time`` deep-link parameter."""
    log = open_log(log_path)
    end_ns = log.time_origin_ns + log.ticks[-1].stamp_ns
    when = datetime.datetime.fromtimestamp(end_ns / 1e9, datetime.UTC)
    return when.isoformat(timespec="milliseconds").replace("+00:00", "Z")


@pytest.fixture(scope="module")
def pick_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    skip_without_browser()
    folder = tmp_path_factory.mktemp("foxglove-log")
    log = folder / "pick.mcap"
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(ROOT / "trees/pick.xml"),
         "--scene", str(ROOT / "scenes/tabletop.yaml"), "--log", str(log), "--quiet"],
        capture_output=True, text=True, timeout=300, cwd=folder, env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return log


def test_recorded_pick_shows_whole_in_foxglove(pick_log: Path, tmp_path: Path) -> None:
    with serving(pick_log.parent, LAYOUT) as server:
        url = server.url_for_file(pick_log.name) + "&time=" + end_time_iso(pick_log)
        report = open_in_studio(url, tmp_path, wait_s=10, screenshot=tmp_path / "studio.png", until=("3d", "image"))
    assert report.errors == []
    assert report.problems == [] and report.problem_count == 0, report.problems
    assert set(ROBOT_LINKS) <= set(report.frames), report.frames
    assert {"world", "camera_color_optical_frame"} <= set(report.frames)
    assert report.three_d_drawn, "the 3D panel drew nothing"
    assert report.image_drawn, "the image panel drew nothing"
