"""Where a log's chunks end must not depend on the machine's speed (issue 27: "a log must stay byte-identical
for the same seed whatever the machine's speed"). Episodes used to end a chunk at the first tick after 50 ms of
wall time, so a slow and a fast machine wrote the same messages in different chunks. Now a chunk ends every N
ticks, counted by the recorder; the wall clock the test jumps around changes nothing."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from mcap.records import Chunk
from mcap.stream_reader import StreamReader

from bt_grasp.recording.writer import RunRecorder

FIXED_ORIGIN = 1_700_000_000_000_000_000


def _record(path: Path, every: int, monotonic_steps: list[float], monkeypatch: pytest.MonkeyPatch) -> bytes:
    clock = itertools.accumulate(itertools.cycle(monotonic_steps))
    monkeypatch.setattr("bt_grasp.recording.writer.time.monotonic", lambda: next(clock))
    with RunRecorder(path, metadata={"tree": "t"}, wall_clock=lambda: FIXED_ORIGIN, time_origin_ns=FIXED_ORIGIN,
                     flush_every_ticks=every, handle_signals=False) as rec:
        for tick in range(45):
            rec.write_tick(tick, tick * 10_000_000, [], {"tick": tick})
            rec.flush_tick()
    return path.read_bytes()


def _chunks(path: Path) -> int:
    with path.open("rb") as stream:
        return sum(isinstance(record, Chunk) for record in StreamReader(stream, emit_chunks=True).records)


def test_chunks_end_every_n_ticks_whatever_the_wall_clock(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fast = _record(tmp_path / "fast.mcap", 10, [0.0001], monkeypatch)  # a fast machine: 0.1 ms a tick
    slow = _record(tmp_path / "slow.mcap", 10, [0.5, 0.001, 2.0], monkeypatch)  # a loaded one, uneven
    assert fast == slow
    assert _chunks(tmp_path / "fast.mcap") == 5  # ticks 0-9, 10-19, 20-29, 30-39 flushed; 40-44 at close


def test_every_tick_flushes_by_default(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _record(tmp_path / "each.mcap", 1, [0.0001], monkeypatch)
    assert _chunks(tmp_path / "each.mcap") == 45


def test_a_flush_count_below_one_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="flush_every_ticks"):
        RunRecorder(tmp_path / "x.mcap", metadata={}, flush_every_ticks=0, handle_signals=False)
