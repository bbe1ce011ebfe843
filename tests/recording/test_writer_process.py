"""The log written by a child process: the same messages as in-process, a killed parent's log finished by the
child, and the child's failures reported with a sentence."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.recording.reader import open_log
from bt_grasp.recording.robot_model import default_robot_model
from bt_grasp.recording.writer import RunRecorder
from bt_grasp.recording.writer_process import ProcessWriter, WriterProcessError

TOPICS = ("/bt/tick", "/robot/joint_state", "/tf")
REPO = Path(__file__).resolve().parents[2]
WRITER_PARENT = Path(__file__).with_name("record_via_writer_process.py")
#: the kill comes once the parent has reported this many ticks flushed
KILL_AFTER = 50


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


def test_a_killed_parent_loses_no_tick_it_handed_to_the_writer_process(tmp_path: Path) -> None:
    """SIGKILL the process that records through the writer process (the writer ``bt-grasp run --log`` uses) while
    it is writing ticks as fast as it can, then read the log the writer process finished.

    "Flushed" for the writer process: ``flush()`` queues the tick's batch, and the feeder thread writes it to the
    writer process's stdin and flushes that pipe; once that returned, the batch is in the kernel's pipe (or read
    already), which outlives the parent, and the writer process reads its input to the end and finishes the file.
    The parent (``record_via_writer_process.py``) prints ``flushed N`` after each such pipe flush, a count taken
    outside the file; every tick it printed before the kill must be in the log, which must be finished (summary
    and footer written by the writer process). The writer process is stopped (SIGSTOP) from the start until the
    parent is dead, so every batch handed over is still in the pipe at the kill, whatever the machine's speed
    (KILL_AFTER ticks fit in a 64 KiB pipe); the kill is made when the parent has reported KILL_AFTER ticks and is
    still running (it records up to a million), so it always lands mid-run."""
    out = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, str(WRITER_PARENT), str(out)], stdout=subprocess.PIPE, text=True,
                            cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        assert proc.stdout is not None
        first = proc.stdout.readline().split()
        assert first[:1] == ["writer"], first
        writer_pid = int(first[1])
        os.kill(writer_pid, signal.SIGSTOP)
        reported: list[int] = []
        while not reported or reported[-1] < KILL_AFTER:
            line = proc.stdout.readline()
            assert line.startswith("flushed "), f"the parent stopped before tick {KILL_AFTER}: {line!r}"
            reported.append(int(line.split()[1]))
        assert proc.poll() is None, "the parent finished before the kill"
        proc.send_signal(signal.SIGKILL)
        assert proc.wait(timeout=30) == -signal.SIGKILL
        # everything it printed, it printed before the kill: the rest of its output counts too
        reported += [int(line.split()[1]) for line in proc.stdout.read().splitlines()]
        proc.stdout.close()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        with contextlib.suppress(NameError, ProcessLookupError):
            os.kill(writer_pid, signal.SIGCONT)  # the parent is dead: the writer reads its input to the end
    assert reported == list(range(1, len(reported) + 1)), "the parent reported ticks out of order"
    _wait_until_gone(writer_pid, timeout_s=120)  # it read its input to the end and finished the file
    run = open_log(out)
    assert run.indexed and not run.truncated  # summary and footer written by the writer process
    ticks = [t.tick for t in run.ticks]
    assert ticks[: len(reported)] == reported, f"{len(reported)} ticks flushed before the kill, {len(ticks)} in the log"
    assert ticks == list(range(1, len(ticks) + 1))  # and no tick later than those lost in between


def _wait_until_gone(pid: int, *, timeout_s: float) -> None:
    """Wait until a process that is not this one's child has exited (gone, or a zombie of its new parent)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return
        if state == "Z":
            return
        time.sleep(0.05)
    raise AssertionError(f"the writer process {pid} did not finish within {timeout_s:g} s")


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
