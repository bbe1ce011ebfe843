"""Recordings written by pyrealsense2's own recorder from a software device, played back through its pipeline
(issue 39): every frame in order with the streams' intrinsics, depth scale and extrinsics; a truncated or foreign
file, a wrist camera's recording without its tool poses, a poses file out of shape and a calibration made with other
intrinsics are each one sentence and exit code 2, never a traceback."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from rs_fixtures import H, W, streams, write_recording

from bt_grasp.cli.main import main
from bt_grasp.errors import InputError
from bt_grasp.hardware.realsense_open import open_recording
from bt_grasp.hardware.recording_file import RecordingError, RecordingFormat, check_recording, frames_held
from bt_grasp.hardware.tool_poses import ToolPose, poses_path, read_poses, write_poses

REPO = Path(__file__).resolve().parents[2]
PREFIX = "bt-grasp: error: "


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[tuple[np.ndarray, np.ndarray]]]:
    path = tmp_path_factory.mktemp("recordings") / "synthetic.db3"
    return path, write_recording(path, 12)


def test_every_frame_plays_back_in_order_through_the_pipeline_and_align(recording: tuple) -> None:
    path, written = recording
    assert check_recording(path) is RecordingFormat.DB3
    held = frames_held(path)  # what a playback that came back short is told the file holds
    assert sorted(held.values()) == [12, 12] and all("/image/data" in name for name in held), held
    with open_recording(path) as camera:
        info = camera.info
        frames = []
        while (frame := camera.capture()) is not None:
            frames.append(frame)
        assert camera.capture() is None  # the end stays the end
    assert info.color == streams(same_imager=True).color and info.depth == info.color
    assert info.depth_scale_m == pytest.approx(0.001) and np.allclose(info.T_color_depth, np.eye(4), atol=1e-7)
    assert info.serial == "000000000001" and info.color_format == "rgb8"
    assert len(frames) == len(written) == 12
    for k, (frame, (depth, color)) in enumerate(zip(frames, written, strict=True)):
        assert frame.stamp_ns == 1_000_000_000 + k * 33_333_333  # device time, as pushed (ms double: exact here)
        assert np.array_equal(frame.color, color)  # the recorder's colour compression is lossless
        expected = np.round(depth / 0.001).astype(np.uint16).astype(np.float32) * np.float32(info.depth_scale_m)
        # aligned onto an identical imager: the Z16 written, scaled, except where rs.align's pixel-rectangle fill
        # leaves a hole or a neighbour's value (measured: 3 % holes and 1.5 % neighbours on this 64x48 picture)
        valid = frame.depth_m > 0
        assert valid.mean() > 0.95 and (frame.depth_m[valid] == expected[valid]).mean() > 0.95


def test_a_one_frame_recording_gives_its_frame_at_every_opening(tmp_path: Path) -> None:
    """The playback is opened paused and resumed once both sensors stream (bt_grasp.hardware.realsense_open): its
    only pair is never read before the colour sensor starts, and its status never reads "stopped" before it
    played. A 1-frame household recording came back empty once in CI; 15 openings here, each its frame, then the
    end."""
    path = tmp_path / "one.db3"
    ((_depth, color),) = write_recording(path, 1)
    for _ in range(15):
        with open_recording(path) as camera:
            frame = camera.capture()
            assert frame is not None and np.array_equal(frame.color, color)
            assert camera.capture() is None and camera.captures == 1


def test_extrinsics_and_intrinsics_come_from_the_stream_profiles(tmp_path: Path) -> None:
    path = tmp_path / "offset.db3"
    write_recording(path, 2, same_imager=False)
    with open_recording(path) as camera:
        frame = camera.capture()
        info = camera.info
    assert info.depth.fx_px == pytest.approx(38.0) and info.color.fx_px == pytest.approx(60.0)
    assert info.T_color_depth[:3, 3] == pytest.approx([0.015, 0.0, 0.0], abs=1e-7)
    assert frame is not None and frame.intrinsics == info.color and frame.depth_m.shape == (H, W)


def _truncated(recording: Path, tmp_path: Path) -> Path:
    data = recording.read_bytes()
    out = tmp_path / "truncated.db3"
    out.write_bytes(data[: len(data) - 4096])
    return out


BAD_FILES = {
    "png.db3": (b"\x89PNG\r\n\x1a\n" + bytes(200), "is neither a RealSense recording"),
    "empty.db3": (b"", "is empty"),
    "garbage.bag": (b"#ROSBAG V2.0\n" + bytes(64), "pyrealsense2 cannot play it"),
}


@pytest.mark.parametrize("name", [*BAD_FILES, "truncated.db3", "other.db3", "folder.db3", "missing.db3"])
def test_a_truncated_or_foreign_recording_is_one_sentence_and_exit_2(
    name: str, recording: tuple, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / name
    if name in BAD_FILES:
        path.write_bytes(BAD_FILES[name][0])
        problem = BAD_FILES[name][1]
    elif name == "truncated.db3":
        path, problem = _truncated(recording[0], tmp_path), "is truncated"
    elif name == "other.db3":
        with sqlite3.connect(path) as db:
            db.execute("CREATE TABLE notes (text)")
        problem = "is an SQLite database but not a RealSense recording"
    elif name == "folder.db3":
        path.mkdir()
        problem = "is a folder"
    else:
        problem = "no such file"
    with pytest.raises(RecordingError, match=problem):
        open_recording(path)
    code, out, err = _cli(capsys, "perceive", str(path))
    assert code == 2 and out == ""
    assert err.startswith(PREFIX + str(path)) and problem in err and err.count("\n") == 1, err


def test_a_wrist_cameras_recording_without_tool_poses_is_one_sentence(
    recording: tuple, capsys: pytest.CaptureFixture[str]
) -> None:
    path = recording[0]
    calibration = REPO / "scenes/eye_in_hand.calibration.yaml"
    code, out, err = _cli(capsys, "perceive", str(path), "--calibration", str(calibration))
    assert code == 2 and out == ""
    assert "no tool poses lie beside it (synthetic.poses.jsonl)" in err and err.count("\n") == 1, err


def test_a_calibration_made_with_other_intrinsics_is_refused(recording: tuple, capsys: pytest.CaptureFixture[str]
                                                            ) -> None:
    code, out, err = _cli(capsys, "perceive", str(recording[0]), "--calibration",
                          str(REPO / "scenes/tabletop.calibration.yaml"))
    assert code == 2 and out == ""
    assert "does not fit this camera: it was made for a 640x480 picture, but the source's colour stream is 64x48" in err


def test_tool_poses_round_trip_bit_for_bit_and_a_bad_line_names_its_line(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    from scipy.spatial.transform import Rotation

    poses = []
    for k in range(3):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
        T[:3, 3] = rng.normal(size=3)
        poses.append(ToolPose(1000 + k, T))
    path = write_poses(poses_path(tmp_path / "rec.db3"), poses)
    assert path.name == "rec.poses.jsonl"
    back = read_poses(path)
    assert [back[p.stamp_ns].T_base_tool.tobytes() for p in poses] == [p.T_base_tool.tobytes() for p in poses]
    lines = path.read_text().splitlines()
    for bad, problem in (('{"stamp_ns": 1}', "a line is an object with"), ("not json", "is not JSON lines"),
                         (lines[0].replace('"stamp_ns": 1000', '"stamp_ns": -1'), "non-negative integer"),
                         (lines[0].replace("1.0]]", "2.0]]"), "rigid transform"), (lines[0], "appears twice")):
        path.write_text("\n".join([lines[0], bad]) + "\n")
        with pytest.raises(InputError, match=problem) as info:
            read_poses(path)
        assert info.value.where == "line 2"
    path.write_bytes(json.dumps([1]).encode() + b"\n\xff\n")
    with pytest.raises(InputError, match="is not UTF-8"):
        read_poses(path)
