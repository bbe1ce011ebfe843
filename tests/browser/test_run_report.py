"""`bt-grasp replay LOG --report report.html` on a run failed by an injected fault: one self-contained page that
headless Chromium renders with no network request, whose text names the failure's reason and the leaf, with
every figure drawn; `--report-dir` writes the PNGs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from studio_driver import render_page, skip_without_browser

from bt_grasp.recording.reader import open_log

ROOT = Path(__file__).resolve().parents[2]

pytestmark = [pytest.mark.sim]


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], capture_output=True, text=True,
                          timeout=300, cwd=cwd, env={**os.environ, "PYTHONPATH": str(ROOT)})


def test_report_of_an_injected_fault_run_renders_offline(tmp_path: Path) -> None:
    skip_without_browser()
    log = tmp_path / "fault.mcap"
    run = _cli("run", str(ROOT / "trees/pick.xml"), "--scene", str(ROOT / "scenes/tabletop.yaml"),
               "--inject", "frame_drop@Perceive#1", "--log", str(log), "--quiet", cwd=tmp_path)
    assert run.returncode == 1, run.stdout + run.stderr  # pick.xml has no recovery: the dropped frame fails it
    result = open_log(log).result
    assert result is not None and result["reason"] and result["failed_leaf"] == "Perceive"

    html, figures = tmp_path / "report.html", tmp_path / "figures"
    made = _cli("replay", str(log), "--report", str(html), "--report-dir", str(figures), cwd=tmp_path)
    assert made.returncode == 0, made.stdout + made.stderr
    assert {"gantt.png", "joints.png", "gripper.png"} <= {p.name for p in figures.iterdir()}

    page = render_page(html.as_uri(), tmp_path, tmp_path / "report.png")
    assert [u for u in page["requests"] if not u.startswith(("file:", "data:"))] == []  # no network
    text = page["text"]
    assert result["reason"] in text and "Perceive" in text and "FAILURE" in text
    assert "Failures and recovery" in text and "Leaf statuses over time" in text
    assert page["images"] and all(w > 100 and h > 100 for w, h in page["images"])
    shot = cv2.imread(str(tmp_path / "report.png"))
    assert shot is not None and shot.shape[0] > 1000  # the whole page, figures included
    assert len(np.unique((shot // 16).reshape(-1, 3), axis=0)) > 50  # drawn, not blank
