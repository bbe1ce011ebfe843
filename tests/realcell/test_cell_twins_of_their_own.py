"""Issue 41 against twins of their own (each test starts one: a twin is a few seconds; what it runs is the time):
calibration on the cell (done-when 2), the twin killed mid-motion (done-when 3's fault that takes its twin with it),
and the shipped trees unchanged through the twin (done-when 4; `pick_with_recovery` is
``test_cell_on_twin.py``'s)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("rtde_control", reason="ur_rtde is not installed (pip install -e '.[hardware]')")
pytest.importorskip("pyrealsense2", reason="pyrealsense2 is not installed (pip install -e '.[hardware]')")

from bt_grasp.bench.cell_faults import SHUTTLE_TREE, one_trial
from bt_grasp.bench.twin_process import start_twin

pytestmark = [pytest.mark.sim, pytest.mark.slow, pytest.mark.real_client]

REPO = Path(__file__).resolve().parents[2]


def _bt(*args: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], cwd=REPO, capture_output=True,
                          text=True, timeout=timeout, check=False)


def test_calibrate_on_the_cell_lands_within_1_mm_and_0_1_degree_of_the_twins_camera(tmp_path: Path) -> None:
    from bt_grasp.geometry import pose_error
    from bt_grasp.perception.calibration_file import load_calibration

    # the table cleared, as docs/real-cell.md's checklist asks before calibrating: calibration moves the arm before
    # anything is perceived, and its planner knows the table and the fixtures, not the objects (the twin's tabletop
    # objects were brushed by a view's path at 150-200 N: a protective stop)
    scene = yaml.safe_load((REPO / "scenes/tabletop.yaml").read_text())
    scene["objects"] = []
    cleared = tmp_path / "tabletop_cleared.yaml"
    cleared.write_text(yaml.safe_dump(scene, sort_keys=False))
    twin = start_twin(cleared, tmp_path, "--board", repo=REPO, salt=7)
    try:
        cell = tmp_path / "cell.yaml"
        cell.write_text(twin.cell_path.read_text().replace("calibration: ", "calibration: twin.calibration.yaml #"))
        done = _bt("calibrate", "--cell", str(cell), "--yes", "--poses", "12", "--json")
        assert done.returncode == 0, done.stderr[-3000:] + "\n--- the twin's log ---\n" + twin.log()[-3000:]
        summary = json.loads(done.stdout)
        assert summary["out"] == str(tmp_path / "twin.calibration.yaml") and summary["ran_on"] == "twin"
        truth = np.array(twin.control("truth camera")["T_true"])  # the twin's judge side: for this test only
    finally:
        assert twin.stop() == 0
    calibration = load_calibration(tmp_path / "twin.calibration.yaml", mount="eye-to-hand")
    error_m, error_rad = pose_error(calibration.T_base_camera_at(), truth)
    print(f"calibrate --cell through the twin: {error_m * 1000:.3f} mm, {np.degrees(error_rad):.4f} deg from the "
          f"true camera pose ({summary['samples']} views, residual {summary['residual_mm']} mm, "
          f"{summary['elapsed_s']} s)")
    assert error_m < 0.001 and np.degrees(error_rad) < 0.1


def test_the_twin_killed_mid_motion_ends_the_run_connection_lost(tmp_path: Path) -> None:
    twin = start_twin("scenes/tabletop.yaml", tmp_path, repo=REPO, salt=9)
    tree = tmp_path / "shuttle.xml"
    tree.write_text(SHUTTLE_TREE)
    try:
        trial = one_trial("twin-killed", twin, tree, tmp_path, 0)
    finally:
        twin.stop()
    assert trial.reason == "CONNECTION_LOST", trial
    assert trial.seen_ms is not None and trial.seen_ms < 1000.0, trial
    assert trial.replayed and trial.exit_code == 1, trial


@pytest.mark.parametrize(("tree", "scene"), [("trees/pick.xml", "scenes/tabletop.yaml"),
                                             ("trees/pick_and_place.xml", "scenes/pick_and_place.yaml")])
def test_the_shipped_trees_run_unchanged_through_the_twin(tmp_path: Path, tree: str, scene: str) -> None:
    twin = start_twin(scene, tmp_path, repo=REPO, salt=11)
    summary = tmp_path / "summary.json"
    try:
        done = _bt("run", tree, "--cell", str(twin.cell_path), "--yes", "--quiet", "--summary-json", str(summary))
    finally:
        twin.stop()
    result = json.loads(summary.read_text())
    assert done.returncode == 0, (result, done.stderr[-3000:])
    assert result["success"] and result["judge"]["source"] == "the twin's physics judge"
    assert result["goal"]["kind"] == ("place" if "place" in tree else "pick")  # the twin scene's own goal
