"""A recorded run of a mesh scene (scenes/household.yaml: a standing bottle, a ring, a box upside down) opened in
the real Foxglove Studio web build 1.48 with the shipped layout, the judge's true objects made visible so the 3D
panel loads their embedded STL models: no problem for any topic, every robot link known, the 3D panel draws."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from studio_driver import ROBOT_LINKS, open_in_studio, serving, skip_without_browser
from test_foxglove_log import LAYOUT, end_time_iso

from bt_grasp.recording.reader import open_log

ROOT = Path(__file__).resolve().parents[2]

pytestmark = [pytest.mark.sim, pytest.mark.slow]


@pytest.fixture(scope="module")
def mesh_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    skip_without_browser()
    folder = tmp_path_factory.mktemp("foxglove-mesh-log")
    log = folder / "household.mcap"
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(ROOT / "trees/pick.xml"),
         "--scene", str(ROOT / "scenes/household.yaml"), "--seed", "4", "--color", "green", "--max-ticks", "300",
         "--log", str(log), "--quiet"],
        capture_output=True, text=True, timeout=600, cwd=folder,
        env={**os.environ, "PYTHONPATH": str(ROOT), "BT_GRASP_CACHE_DIR": str(folder / "cache")},
    )
    assert log.is_file(), proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    return log


def test_a_mesh_scene_log_shows_in_foxglove_with_no_problem(mesh_log: Path, tmp_path: Path) -> None:
    truths = [m.message for m in open_log(mesh_log).iter_messages("/judge/true_objects")]
    models = {e.id: len(e.models) for e in truths[0].entities}
    assert models == {"true/true bottle": 1, "true/true ring": 1, "true/true small_box": 1}, models
    layout = json.loads(LAYOUT.read_text())
    shown = 0
    for config in layout["configById"].values():
        topics = config.get("topics", {}) if isinstance(config, dict) else {}
        if "/judge/true_objects" in topics:
            topics["/judge/true_objects"]["visible"] = True  # hidden in the shipped layout: show the models
            shown += 1
    assert shown == 1
    visible_layout = tmp_path / "layout.json"
    visible_layout.write_text(json.dumps(layout))
    with serving(mesh_log.parent, visible_layout) as server:
        url = server.url_for_file(mesh_log.name) + "&time=" + end_time_iso(mesh_log)
        report = open_in_studio(url, tmp_path, wait_s=10, screenshot=tmp_path / "studio.png", until=("3d",))
    assert report.errors == []
    assert report.problems == [] and report.problem_count == 0, report.problems
    assert set(ROBOT_LINKS) <= set(report.frames), report.frames
    assert "world" in report.frames
    assert report.three_d_drawn, "the 3D panel drew nothing"
