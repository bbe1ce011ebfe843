"""The live server (foxglove-sdk) and wall-clock pacing, without a simulator or a browser."""

from __future__ import annotations

import socket
import time
from typing import Any

import pytest

from bt_grasp.episode.observers import RealtimePacer
from bt_grasp.foxglove.live import LiveServer, LiveServerError
from bt_grasp.recording import topics
from bt_grasp.recording.writer import RunRecorder


class FakeWorld:
    def __init__(self) -> None:
        self.t_ns = 0

    def now_ns(self) -> int:
        return self.t_ns


def test_pacer_makes_wall_time_follow_simulated_time() -> None:
    world = FakeWorld()
    pacer = RealtimePacer(world, factor=2.0)  # two simulated seconds per wall second
    start = time.monotonic()
    for tick in range(11):
        pacer(tick, None)  # type: ignore[arg-type]
        world.t_ns += 20_000_000  # 20 ms of simulated time per tick
    elapsed = time.monotonic() - start
    assert 0.09 <= elapsed < 0.5  # 200 ms simulated / 2 = 100 ms of wall time, not less


def test_pacer_refuses_a_non_positive_factor() -> None:
    with pytest.raises(ValueError, match="positive"):
        RealtimePacer(FakeWorld(), factor=0.0)


def test_live_server_advertises_the_recorders_topics_and_forwards_without_a_file() -> None:
    server = LiveServer(port=0)
    try:
        assert server.url.startswith("ws://127.0.0.1:") and server.port > 0
        recorder = RunRecorder(None, metadata={}, handle_signals=False)  # a live stream only: no file
        server.attach(recorder)
        assert set(server._channels) == {*topics.JSON_TOPICS, *topics.PROTOBUF_TOPICS}
        recorder.write_log(0, "INFO", "test", "hello")
        recorder.write_tick(1, 10_000_000, [], {}, {"q_rad": [0.0] * 6})
        recorder.close()
        assert server.dropped_errors == 0
        with socket.socket() as s:  # it listens on loopback
            assert s.connect_ex(("127.0.0.1", server.port)) == 0
    finally:
        server.close()


def test_a_taken_port_is_one_clear_sentence() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(LiveServerError, match=f"cannot serve a live view on 127.0.0.1:{port}"):
            LiveServer(port=port)


def test_taps_see_every_message_with_the_files_time(tmp_path: Any) -> None:
    seen: list[tuple[str, int]] = []
    with RunRecorder(tmp_path / "r.mcap", metadata={}, handle_signals=False, time_origin_ns=5_000) as rec:
        rec.add_tap(lambda topic, t, data: seen.append((topic, t)))
        rec.write_log(100, "INFO", "x", "y")
    assert seen == [(topics.LOG, 5_100)]


def test_a_frame_captured_while_nobody_watched_reaches_the_first_viewer() -> None:
    """A live-only run skips encoding while nobody watches; the last capture is sent at the first watched tick
    (stamped with its capture time), so a viewer joining after Perceive still sees the picture."""
    import numpy as np

    from bt_grasp.episode.media import RecorderSink
    from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame

    watching = {"now": False}
    seen: list[tuple[str, int]] = []
    recorder = RunRecorder(None, metadata={}, handle_signals=False)
    recorder.add_tap(lambda topic, t, data: seen.append((topic, t)), wanted=lambda: watching["now"])
    now = {"ns": 30_000_000}
    sink = RecorderSink(recorder, lambda: now["ns"])
    intr = CameraIntrinsics(8, 6, 10.0, 10.0, 4.0, 3.0)
    depth = np.full((6, 8), 0.5, dtype=np.float32)
    for shade in (10, 200):  # two captures while unwatched: only the last one is kept
        frame = RGBDFrame(np.full((6, 8, 3), shade, dtype=np.uint8), depth, intr, now["ns"], Mount.EYE_TO_HAND)
        sink.frame(frame, np.eye(4))
        now["ns"] += 10_000_000
    recorder.write_tick(5, now["ns"], [], {})
    assert [t for t, _ in seen if t == topics.COLOR] == []  # nobody watched: nothing encoded
    watching["now"] = True
    recorder.write_tick(6, now["ns"] + 10_000_000, [], {})
    colour = [(t, stamp) for t, stamp in seen if t in (topics.COLOR, topics.CALIBRATION, topics.POINTS)]
    at = recorder.t(40_000_000)  # the second capture's time, not the tick's
    assert sorted(colour) == sorted([(topics.COLOR, at), (topics.CALIBRATION, at), (topics.POINTS, at)])
    recorder.write_tick(7, now["ns"] + 20_000_000, [], {})
    assert sum(1 for t, _ in seen if t == topics.COLOR) == 1  # sent once, not at every tick
    recorder.close()
