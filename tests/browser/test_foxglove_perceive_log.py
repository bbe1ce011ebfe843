"""`perceive --log` on a RealSense recording of the household scene (issue 39, done-when 3), opened in the real
Foxglove Studio web build 1.48 with the shipped layout: no problem for any topic, the 3D and image panels draw, the
ranked grasps are drawn as grippers (a 3D panel showing nothing but /perception/grasps, close up, draws their green
and blue) and the point cloud is drawn (a 3D panel showing nothing but it draws a picture). The screenshots in
docs/images/foxglove-perceive*.png are this test's (``BT_GRASP_SCREENSHOTS`` set to a folder keeps them there)."""

from __future__ import annotations

import datetime
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from studio_driver import _coloured, _drawn, open_in_studio, serving, skip_without_browser
from test_foxglove_log import LAYOUT

ROOT = Path(__file__).resolve().parents[2]

pytestmark = [pytest.mark.sim, pytest.mark.slow]


def _bt(*args: object, cwd: Path) -> None:
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stdout + proc.stderr


@pytest.fixture(scope="module")
def perceive_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    skip_without_browser()
    pytest.importorskip("pyrealsense2", reason="the realsense extra is not installed")
    folder = tmp_path_factory.mktemp("foxglove-perceive")
    rec, log = folder / "household.db3", folder / "household.mcap"
    _bt("camera", "record", "--scene", ROOT / "scenes/household.yaml", "--seed", 0, "--out", rec, cwd=folder)
    _bt("perceive", rec, "--calibration", ROOT / "scenes/tabletop.calibration.yaml", "--detector", "learned",
        "--log", log, cwd=folder)
    return log


def _end_iso(log: Path) -> str:
    from mcap.reader import make_reader

    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    when = datetime.datetime.fromtimestamp(summary.statistics.message_end_time / 1e9, datetime.UTC)
    return when.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _keep(shot: Path, name: str) -> None:
    folder = os.environ.get("BT_GRASP_SCREENSHOTS")
    if folder and shot.is_file():
        shutil.copy(shot, Path(folder) / name)


def test_a_perceive_log_shows_whole_in_foxglove(perceive_log: Path, tmp_path: Path) -> None:
    with serving(perceive_log.parent, LAYOUT) as server:
        url = server.url_for_file(perceive_log.name) + "&time=" + _end_iso(perceive_log)
        report = open_in_studio(url, tmp_path, wait_s=10, screenshot=tmp_path / "studio.png", until=("3d", "image"))
    _keep(tmp_path / "studio.png", "foxglove-perceive.png")
    assert report.errors == []
    assert report.problems == [] and report.problem_count == 0, report.problems
    assert {"world", "base_link", "camera_color_optical_frame"} <= set(report.frames), report.frames
    assert report.three_d_drawn, "the 3D panel drew nothing"
    assert report.image_drawn, "the image panel drew nothing"


def _only(topic: str, folder: Path) -> Path:
    """The shipped layout with a 3D panel showing nothing but ``topic`` (no grid), close over the table."""
    layout = json.loads(LAYOUT.read_text())
    three_d = layout["configById"]["3D!arm"]
    three_d["layers"]["grid"]["visible"] = False
    three_d["topics"] = {name: {**settings, "visible": name == topic} for name, settings in three_d["topics"].items()}
    three_d["cameraState"].update({"distance": 0.7, "targetOffset": [0.45, 0.0, 0.05], "phi": 30})
    path = folder / "only.layout.json"
    path.write_text(json.dumps(layout))
    return path


def _three_d_panels(perceive_log: Path, layout: Path, folder: Path, shot: str) -> list[Path]:
    with serving(perceive_log.parent, layout) as server:
        url = server.url_for_file(perceive_log.name) + "&time=" + _end_iso(perceive_log)
        report = open_in_studio(url, folder, wait_s=10, screenshot=folder / shot, until=("3d",))
    _keep(folder / shot, f"foxglove-perceive-{shot}")
    assert report.problems == [], report.problems
    return [Path(p["file"]) for p in report.raw.get("panels", []) if p.get("kind") == "3d" and "file" in p]


def test_the_grasps_are_drawn_as_grippers(perceive_log: Path, tmp_path: Path) -> None:
    panels = _three_d_panels(perceive_log, _only("/perception/grasps", tmp_path), tmp_path, "grasps.png")
    assert panels and any(_coloured(p) for p in panels), "no gripper drawn in a 3D panel showing only the grasps"


def test_the_point_cloud_is_drawn(perceive_log: Path, tmp_path: Path) -> None:
    panels = _three_d_panels(perceive_log, _only("/perception/points", tmp_path), tmp_path, "points.png")
    assert panels and any(_drawn(p) for p in panels), "no point drawn in a 3D panel showing only the cloud"
