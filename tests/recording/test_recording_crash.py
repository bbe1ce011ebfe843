"""Crash tolerance: a killed writer leaves a readable prefix; SIGTERM/SIGINT finish the file; cut files."""

from __future__ import annotations

import contextlib
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bt_grasp.errors import LogFileError
from bt_grasp.recording import open_log

CHILD = Path(__file__).with_name("record_forever.py")


def _start(out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, str(CHILD), str(out)], stdout=subprocess.PIPE, text=True)


def _read_until(proc: subprocess.Popen[str], n_lines: int) -> list[int]:
    assert proc.stdout is not None
    flushed = []
    deadline = time.monotonic() + 60
    while len(flushed) < n_lines and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        flushed.append(int(line))
    return flushed


def test_sigkill_keeps_every_flushed_tick(tmp_path):
    out = tmp_path / "killed.mcap"
    proc = _start(out)
    flushed = _read_until(proc, 150)
    proc.kill()  # SIGKILL: no handler, no footer
    proc.communicate(timeout=10)
    assert len(flushed) == 150
    run = open_log(out)
    assert run.truncated and not run.indexed
    # every tick the child reported flushed before the kill is there, in order
    assert run.ticks_recovered >= flushed[-1] + 1
    assert [t.tick for t in run.ticks][: flushed[-1] + 1] == list(range(flushed[-1] + 1))
    assert run.metadata["tree_file"] == "kill.xml"
    assert run.blackboard_at(flushed[-1]) == {"tick": flushed[-1]}


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_sigterm_and_sigint_finish_the_file(tmp_path, signum):
    out = tmp_path / "terminated.mcap"
    proc = _start(out)
    try:
        flushed = _read_until(proc, 50)
        proc.send_signal(signum)
        proc.communicate(timeout=30)
    finally:  # a child that outlives a failed test must not leak into the next one
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=10)
    assert proc.returncode != 0
    run = open_log(out)
    assert not run.truncated and run.indexed  # footer and summary written on the way out
    assert run.ticks_recovered >= len(flushed)
    assert run.events[-1]["kind"] == "aborted"


def _cut(src: Path, dst: Path, size: int) -> Path:
    dst.write_bytes(src.read_bytes()[:size])
    return dst


def test_files_cut_at_any_offset_read_as_truncated(make_run, tmp_path):
    src, written = make_run("full.mcap", grasp_failures=5, max_ticks=60)
    data_len = src.stat().st_size
    full = open_log(src)
    last_ticks = -1
    for offset in range(8, data_len, max(1, data_len // 97)):
        cut = _cut(src, tmp_path / "cut.mcap", offset)
        try:
            run = open_log(cut)
        except LogFileError as exc:
            # only a cut before the run metadata is complete may be refused, with one sentence
            assert "cut off" in str(exc) and "cut.mcap" in str(exc)
            assert last_ticks == -1
            continue
        assert run.truncated
        assert run.ticks == full.ticks[: run.ticks_recovered]  # a prefix, never garbage
        assert run.ticks_recovered >= last_ticks  # more bytes never give fewer ticks
        last_ticks = run.ticks_recovered
    assert last_ticks == written["n_ticks"]  # a cut inside the summary loses no tick


def test_file_without_summary_reads_linearly(ok_run, tmp_path):
    path, written = ok_run
    data = path.read_bytes()
    # drop the footer magic only: the seeking reader cannot be used, everything else is intact
    run = open_log(_cut(path, tmp_path / "nomagic.mcap", len(data) - 8))
    assert run.truncated and not run.indexed
    assert run.ticks_recovered == written["n_ticks"]
    assert run.result == written["result"]
    assert len(list(run.images())) == 4


def test_a_swallowed_interrupt_is_raised_again_at_the_next_record():
    """A handler can run inside a finalizer, where Python ignores what it raises: the signal must not be lost."""
    from bt_grasp.recording.signals import SignalGuard

    guard = SignalGuard()
    with contextlib.suppress(KeyboardInterrupt):  # what a finalizer does with the handler's exception
        guard._handle(signal.SIGINT, None)
    with pytest.raises(KeyboardInterrupt), guard.busy():
        pass  # the next record written
    guard.acknowledge()
    with guard.busy():  # once the recorder is closing, records are written undisturbed
        pass
