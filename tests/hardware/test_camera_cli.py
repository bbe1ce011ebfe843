"""The camera commands' refusals, each one sentence and exit code 2 (issue 39, done-when 5), and bt_grasp without
the realsense extra: every other command works, asking for a RealSense camera is one sentence."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pyrealsense2 as rs
import pytest

from bt_grasp.cli.device_option import fill_device_value
from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
PREFIX = "bt-grasp: error: "


def _cli(capsys: pytest.CaptureFixture[str], *args: object) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _one_sentence(err: str) -> None:
    assert err.startswith(PREFIX) and err.count("\n") == 1 and "Traceback" not in err, err


@pytest.fixture
def no_device() -> None:
    if len(rs.context().query_devices()):
        pytest.skip("a RealSense device is connected to this machine")


@pytest.mark.usefixtures("no_device")
def test_device_with_no_device_connected_is_one_sentence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _cli(capsys, "perceive", "--device")
    assert code == 2 and out == ""
    _one_sentence(err)
    assert "no RealSense device is connected; check the USB 3 cable and the udev rules" in err
    code, out, err = _cli(capsys, "camera", "record", "--device", "--out", tmp_path / "live.db3", "--seconds", "0.5")
    assert code == 2 and out == "" and not (tmp_path / "live.db3").exists()
    _one_sentence(err)
    code, _, err = _cli(capsys, "perceive", "--device", "123456789012", "--json")
    assert code == 2 and "no RealSense device is connected" in err


def test_a_source_is_exactly_one_and_a_recording_is_a_db3(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for args, problem in ((("perceive",), "nothing was given"),
                          (("perceive", "a.db3", "--device"), "a recording and --device were given"),
                          (("camera", "record", "--out", tmp_path / "x.bag", "--scene", REPO / "scenes/tabletop.yaml"),
                           "a recording is written as .db3"),
                          (("camera", "record", "--out", tmp_path / "x.db3"), "give --scene SCENE"),
                          (("tree", "run", REPO / "trees/pick.xml", "--dry", "--calibration",
                            REPO / "scenes/tabletop.calibration.yaml"), "give it with --camera"),
                          (("tree", "run", REPO / "trees/pick.xml", "--dry", "--camera", tmp_path / "none.db3"),
                           "no such file")):
        code, out, err = _cli(capsys, *args)
        assert code == 2 and out == "", args
        _one_sentence(err)
        assert problem in err, (args, err)


def test_device_takes_its_serial_number_or_none() -> None:
    assert fill_device_value(["perceive", "--device"]) == ["perceive", "--device="]
    assert fill_device_value(["perceive", "--device", "--json"]) == ["perceive", "--device=", "--json"]
    assert fill_device_value(["perceive", "--device", "0123"]) == ["perceive", "--device", "0123"]


_WITHOUT = """
import sys
sys.modules["pyrealsense2"] = None  # as on a machine without the realsense extra: importing it fails
from bt_grasp.cli.main import main
import bt_grasp.hardware.realsense_open, bt_grasp.sensing.perceive_run  # the package imports without it
raise SystemExit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize(("args", "code", "text"), [
    (["perceive", "recording.db3"], 2, "needs pyrealsense2, which is not installed: install the extra with"),
    (["camera", "record", "--scene", "scenes/tabletop.yaml", "--out", "{tmp}/r.db3"], 2, "needs pyrealsense2"),
    (["tree", "validate", "trees/pick_class.xml"], 0, "OK"),
])
def test_without_the_extra_a_realsense_camera_is_one_sentence_and_the_rest_works(
    args: list[str], code: int, text: str, tmp_path: Path
) -> None:
    recording = tmp_path / "recording.db3"
    from rs_fixtures import write_recording

    write_recording(recording, 1)
    argv = [a.replace("{tmp}", str(tmp_path)).replace("recording.db3", str(recording)) for a in args]
    done = subprocess.run([sys.executable, "-c", _WITHOUT, *argv], cwd=REPO, capture_output=True, text=True,
                          timeout=120, env={**os.environ, "PYTHONPATH": str(REPO)})
    assert done.returncode == code, done.stdout + done.stderr
    assert text in done.stdout + done.stderr
    if code:
        _one_sentence(done.stderr)
