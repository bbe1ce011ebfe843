"""Issue 41 against a twin: the real libraries (ur_rtde, pyrealsense2) and bt-grasp's own Robotiq client drive a
twin as they would drive a cell, never a stand-in for them.

One twin (``scenes/tabletop.yaml``, seed 0, its protective stops unlockable after 0.2 s) serves this module; each
test leaves it able to take the next run. Done-when 3: each fault is injected mid-motion into a run in a process of
its own (``bt_grasp.bench.cell_faults.one_trial``, what ``bench cell-faults`` repeats) and must end the run with its
own reason, the arm still and the fault seen within 1 s, and a log ``replay`` reads; a motion leaving the workspace
box is refused before anything is sent. Done-when 1's seed through the real ur_rtde library is
``tests/test_readme_commands.py``'s ``bench twin --seeds 1``."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rtde_control", reason="ur_rtde is not installed (pip install -e '.[hardware]')")
pytest.importorskip("pyrealsense2", reason="pyrealsense2 is not installed (pip install -e '.[hardware]')")

from bt_grasp.bench.cell_faults import EXPECTED, SHUTTLE_TREE, one_trial, recover
from bt_grasp.bench.twin_process import TwinProcess, start_twin

pytestmark = [pytest.mark.sim, pytest.mark.real_client]

REPO = Path(__file__).resolve().parents[2]
BOUND_MS = 1000.0


@pytest.fixture(scope="module")
def twin(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TwinProcess]:
    started = start_twin("scenes/tabletop.yaml", tmp_path_factory.mktemp("twin"), "--unlock-delay", "0.2",
                         repo=REPO, salt=41)
    yield started
    assert started.stop() == 0, started.log()[-3000:]


@pytest.fixture(scope="module")
def shuttle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("trees") / "shuttle.xml"
    path.write_text(SHUTTLE_TREE)
    return path


def _bt(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], cwd=REPO, capture_output=True,
                          text=True, timeout=timeout, check=False)


def test_the_twins_camera_reaches_a_run_through_pyrealsense2(twin: TwinProcess) -> None:
    from bt_grasp.cell.format import load_cell
    from bt_grasp.hardware.twin_camera import TwinD435Camera

    cell = load_cell(twin.cell_path)
    camera = TwinD435Camera(twin.host, cell.camera.port)
    try:
        frame = camera.capture()
        assert frame is not None
        assert camera.camera.info.name.endswith("(bt_grasp twin)")  # read through the RealSense camera class
        assert frame.intrinsics.fx_px == pytest.approx(625.2, abs=0.1) and frame.color.shape == (480, 640, 3)
        valid = frame.depth_m[frame.depth_m > 0]
        assert valid.size > 0.8 * frame.depth_m.size  # aligned by rs.align from the depth imager's own picture
        centre = float(np.median(frame.depth_m[220:260, 300:340]))
        assert 0.9 < centre < 1.1  # the table under the optical axis, ~0.96 m from the camera
        assert camera.capture() is not None  # the next frame: the cell as it is then
    finally:
        camera.close()


@pytest.mark.parametrize("fault", ["protective-stop", "gripper-silent", "sigstop", "ctrl-c"])
def test_a_fault_mid_motion_ends_the_run_with_its_own_reason_the_arm_stopped(twin: TwinProcess, shuttle: Path,
                                                                             tmp_path: Path, fault: str) -> None:
    trial = one_trial(fault, twin, shuttle, tmp_path, 0)
    recover(twin)
    assert trial.reason == EXPECTED[fault], (trial, twin.log()[-2000:])
    assert trial.stop_ms is not None and trial.stop_ms < BOUND_MS, trial
    if fault != "sigstop":  # a stopped process sees nothing until resumed
        assert trial.seen_ms is not None and trial.seen_ms < BOUND_MS, trial
    assert trial.replayed, trial


def test_a_motion_out_of_the_workspace_box_is_refused_before_anything_is_sent(twin: TwinProcess,
                                                                            tmp_path: Path) -> None:
    tree = tmp_path / "out_of_box.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="Out"><MoveTo pose="0.45;0.55;0.25"/></BehaviorTree>'
                    "</root>\n")
    before = np.array(twin.control("status")["actual_q"])
    summary = tmp_path / "summary.json"
    done = _bt("run", str(tree), "--cell", str(twin.cell_path), "--yes", "--summary-json", str(summary))
    assert done.returncode == 1 and "Traceback" not in done.stderr, done.stderr
    result = json.loads(summary.read_text())
    assert result["reason"] == "SAFETY_LIMIT" and result["failed_leaf"] == "MoveTo"
    assert "the TCP would leave the workspace box" in done.stderr  # the leaf's failure line says why
    after = np.array(twin.control("status")["actual_q"])
    assert float(np.max(np.abs(after - before))) < 1e-4  # nothing was sent: the arm never moved


def test_a_run_asks_before_the_first_motion_and_a_non_terminal_must_say_yes(twin: TwinProcess, shuttle: Path) -> None:
    done = _bt("run", str(shuttle), "--cell", str(twin.cell_path))
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("bt-grasp: error: --yes: a run on a real cell asks before the arm's first motion")


@pytest.mark.slow
def test_the_speed_slider_slows_a_run_and_its_checks_follow(twin: TwinProcess, tmp_path: Path) -> None:
    """The executor's tracking and settling checks run on trajectory time, which the slider slows: at 40 % the same
    motion takes about 2.5 times as long and still succeeds (on wall time it would fail TRACKING_ERROR)."""
    rtde_io = pytest.importorskip("rtde_io")
    tree = tmp_path / "there_and_back.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="Go"><Sequence><MoveTo pose="0.50;-0.12;0.22"/>'
                    '<MoveTo pose="0.40;0.12;0.25"/></Sequence></BehaviorTree></root>\n')
    seconds = {}
    io = rtde_io.RTDEIOInterface(twin.host)
    try:
        for number, fraction in enumerate((1.0, 1.0, 0.4)):  # the first brings the arm to where both others start
            assert io.setSpeedSlider(fraction)
            summary = tmp_path / f"slider-{number}.json"
            done = _bt("run", str(tree), "--cell", str(twin.cell_path), "--yes", "--quiet", "--summary-json",
                       str(summary))
            result = json.loads(summary.read_text())  # the twin judges its pick goal: not this tree's, so exit 1
            assert result["tree_status"] == "SUCCESS" and "Traceback" not in done.stderr, (result, done.stderr)
            seconds[fraction] = result["wall_time_s"]
    finally:
        io.setSpeedSlider(1.0)
        io.disconnect()
    assert 1.6 < seconds[0.4] / seconds[1.0] < 3.2, seconds
