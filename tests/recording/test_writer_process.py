"""The log written by a child process: the same messages as in-process, a killed parent's log finished by the
child, and the child's failures reported with a sentence."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.recording.reader import open_log
from bt_grasp.recording.robot_model import default_robot_model
from bt_grasp.recording.writer import RunRecorder
from bt_grasp.recording.writer_process import ProcessWriter, WriterProcessError

TOPICS = ("/bt/tick", "/robot/joint_state", "/tf")


def _record(path: Path, *, writer_process: bool) -> None:
    nodes = [{"uid": 1, "path": "Root", "type": "Sequence", "name": "Root", "kind": "Control", "status": "RUNNING",
              "feedback": "", "failure_reason": None, "ticked": True},
             {"uid": 2, "path": "Root/Move", "type": "MoveTo", "name": "Move", "kind": "Action",
              "status": "RUNNING", "feedback": "", "failure_reason": None, "ticked": True}]
    with RunRecorder(path, metadata={"seed": "3"}, attachments={"tree.xml": b"<root/>"}, time_origin_ns=10**18,
                     robot_model=default_robot_model(), leaf_names=["Move"], writer_process=writer_process) as rec:
        rec.static_transforms[("world", "base_link")] = np.eye(4)
        for tick in range(1, 61):
            if tick == 30:  # a static transform that changes mid-run (as an eye-in-hand camera's does)
                T = np.eye(4)
                T[:3, 3] = [0.1, 0.2, 0.3]
                rec.static_transforms[("base_link", "camera_color_optical_frame")] = T
            q = np.linspace(-1.0, 1.0, 6) * tick / 60.0
            arm = {"q_rad": q.tolist(), "qd_rad_s": np.zeros(6).tolist(), "gripper_width_m": 0.08 - tick * 1e-4}
            rec.write_tick(tick, tick * 10_000_000, nodes, {"target": tick, "name": "red"}, arm)
            rec.flush_tick()
        rec.write_result(600_000_000, {"success": True})


def test_a_child_process_writes_the_same_messages(tmp_path: Path) -> None:
    _record(tmp_path / "inline.mcap", writer_process=False)
    _record(tmp_path / "child.mcap", writer_process=True)
    inline, child = open_log(tmp_path / "inline.mcap"), open_log(tmp_path / "child.mcap")
    assert inline.topics == child.topics and child.topics["/tf"] == 60 and child.result == {"success": True}
    assert child.metadata == inline.metadata and child.attachments == inline.attachments
    for topic in TOPICS:
        a, b = list(inline.iter_messages(topic)), list(child.iter_messages(topic))
        assert [m.log_time_ns for m in a] == [m.log_time_ns for m in b]
        if topic == "/tf":  # protobuf messages: compare what they say
            assert [m.message.SerializeToString() for m in a] == [m.message.SerializeToString() for m in b]
        else:
            assert [m.message for m in a] == [m.message for m in b]
    frames = {t.child_frame_id for t in list(child.iter_messages("/tf"))[-1].message.transforms}
    assert "camera_color_optical_frame" in frames and "wrist_3_link" in frames


def test_the_child_finishes_the_log_of_a_killed_parent(tmp_path: Path) -> None:
    out = tmp_path / "killed.mcap"
    script = textwrap.dedent(f"""
        import sys, time
        import numpy as np
        from bt_grasp.recording.writer import RunRecorder
        rec = RunRecorder({str(out)!r}, metadata={{"seed": "1"}}, writer_process=True, handle_signals=False)
        for tick in range(1, 41):
            rec.write_tick(tick, tick * 10_000_000, [], {{"tick": tick}}, {{"q_rad": [0.0] * 6}})
            rec.flush_tick()
        time.sleep(0.5)  # the feeder thread has written every batch to the pipe
        print("flushed", flush=True)
        time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "flushed"
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    proc.stdout.close()
    for _ in range(100):  # the child sees its input end and finishes the file
        run = open_log(out)
        if run.indexed:
            break
        import time

        time.sleep(0.1)
    assert run.indexed and not run.truncated  # summary and footer written
    assert [t.tick for t in run.ticks] == list(range(1, 41))


def test_an_unwritable_log_fails_before_the_run(tmp_path: Path) -> None:
    with pytest.raises(OSError):
        ProcessWriter(str(tmp_path / "no" / "such" / "dir" / "run.mcap"), chunk_size=1 << 20, compression="zstd",
                      arm_state=None)


def test_a_failing_child_is_reported_with_its_reason(tmp_path: Path) -> None:
    writer = ProcessWriter(str(tmp_path / "bad.mcap"), chunk_size=1 << 20, compression="zstd", arm_state=None)
    writer.start()
    writer.add_arm_state((1, 2), (1, 1), 0, None, {"q_rad": [0.0] * 6})  # but it was told of no arm
    with pytest.raises(WriterProcessError, match="an arm state, but no arm-state settings"):
        writer.finish()
    assert os.path.exists(tmp_path / "bad.mcap")


def test_one_writer_process_writes_file_after_file(tmp_path: Path) -> None:
    """A process that records many episodes starts its writer once: the next file reuses the idle child."""
    from bt_grasp.recording import writer_process

    writer_process.prestart()
    first = ProcessWriter(str(tmp_path / "a.mcap"), chunk_size=1 << 20, compression="zstd", arm_state=None)
    pid = first._process.pid
    first.start("p")
    first.finish()
    second = ProcessWriter(str(tmp_path / "b.mcap"), chunk_size=1 << 20, compression="zstd", arm_state=None)
    assert second._process.pid == pid  # the same child, waiting since the first file
    second.start("p")
    second.finish()
    assert _finished(tmp_path / "a.mcap") and _finished(tmp_path / "b.mcap")


def test_a_failed_writer_process_is_not_reused(tmp_path: Path) -> None:
    bad = ProcessWriter(str(tmp_path / "bad.mcap"), chunk_size=1 << 20, compression="zstd", arm_state=None)
    bad.add_arm_state((1, 2), (1, 1), 0, None, {"q_rad": [0.0] * 6})
    with pytest.raises(WriterProcessError):
        bad.finish()
    good = ProcessWriter(str(tmp_path / "good.mcap"), chunk_size=1 << 20, compression="zstd", arm_state=None)
    assert good._process.pid != bad._process.pid
    good.start("p")
    good.finish()
    assert _finished(tmp_path / "good.mcap")


def _finished(path: Path) -> bool:
    """The file has its summary (written at finish) and the profile the first call named."""
    from mcap.reader import make_reader

    with path.open("rb") as stream:
        reader = make_reader(stream)
        return reader.get_summary() is not None and reader.get_header().profile == "p"
