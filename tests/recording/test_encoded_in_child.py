"""Messages handed to the writer process as their inputs: the child encodes them (the tick's JSON, events,
trajectories, images), and the file is the same, byte for byte, as the one the recorder writes itself."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

from bt_grasp.recording import encodings, writer_process
from bt_grasp.recording.encodings import Encoding, encode, json_bytes
from bt_grasp.recording.jsonable import to_jsonable
from bt_grasp.recording.writer import RunRecorder


class _Opaque:
    """A value JSON cannot hold (its repr is logged)."""

    def __repr__(self) -> str:
        return "<opaque>"


_NODE_FIELDS = {"type": "Action", "kind": "Action", "feedback": "", "failure_reason": None}


def _node(uid: int, path: str, status: str, ticked: bool, kind: str = "Action", **extra: Any) -> dict[str, Any]:
    return {**_NODE_FIELDS, "uid": uid, "path": path, "name": path.rsplit("/", 1)[-1], "kind": kind,
            "status": status, "ticked": ticked, **extra}


def _ticks() -> list[list[dict[str, Any]]]:
    """The nodes of 8 ticks: a sequence of two leaves; a leaf's status changes while it is not ticked (its parent
    reset it); from tick 6 on a third leaf exists (another node set: the leaves' keys are built again)."""
    root = [_node(1, "Seq", "RUNNING", True, kind="Control")]
    a, b, c = "Seq/Move", "Seq/Close", "Seq/Lift"
    return [
        [*root, _node(2, a, "RUNNING", True), _node(3, b, "IDLE", False)],
        [*root, _node(2, a, "RUNNING", True, feedback="halfway"), _node(3, b, "IDLE", False)],
        [*root, _node(2, a, "SUCCESS", True), _node(3, b, "RUNNING", True)],
        [*root, _node(2, a, "SUCCESS", False), _node(3, b, "FAILURE", True, failure_reason="SLIPPED")],
        [*root, _node(2, a, "IDLE", False), _node(3, b, "IDLE", False)],  # reset, not ticked
        [*root, _node(2, a, "RUNNING", True), _node(3, b, "IDLE", False), _node(4, c, "IDLE", False)],
        [*root, _node(2, a, "SUCCESS", True), _node(3, b, "IDLE", False), _node(4, c, "RUNNING", True)],
        [*root, _node(2, a, "SUCCESS", False), _node(3, b, "IDLE", False), _node(4, c, "SUCCESS", True)],
    ]


def _record(path: Path, *, writer_process: bool) -> None:
    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 256, size=(480, 640, 3), dtype=np.uint8)  # 900 KiB: carried beside the pickle
    depth = rng.uniform(0.3, 1.2, size=(480, 640)).astype(np.float32)
    depth[:10] = np.nan
    with RunRecorder(path, metadata={"seed": "5"}, attachments={"tree.xml": b"<root/>"}, time_origin_ns=10**18,
                     wall_clock=lambda: 10**18, leaf_names=["Seq/Move", "Seq/Close"],
                     writer_process=writer_process, handle_signals=False) as rec:
        for tick, nodes in enumerate(_ticks(), start=1):
            stamp = tick * 10_000_000
            blackboard: dict[str, Any] = {"target": "red", "height": 0.1 * tick, "odd": math.nan,
                                          "q": np.arange(6.0) * tick}
            if tick >= 4:
                del blackboard["target"]
            rec.write_tick(tick, stamp, nodes, blackboard, None)
            if tick == 2:
                rec.write_color_image(stamp, rgb, "camera")
                rec.write_depth(stamp, depth, "camera")
                rec.write_trajectory(stamp, "approach", [0.0, 0.5, 1.0], np.ones((3, 6)) * 0.25)
                rec.write_trajectory(stamp, "bad", [0.0, math.inf], np.full((2, 6), math.nan))
            if tick == 4:
                rec.write_event(stamp, "failure", {"leaf": "Close", "why": math.nan, "what": _Opaque()})
            rec.flush_tick()
        rec.write_result(90_000_000, {"success": False, "wall_time_s": 1.5})


def test_the_child_encodes_the_same_file_byte_for_byte(tmp_path: Path) -> None:
    _record(tmp_path / "inline.mcap", writer_process=False)
    _record(tmp_path / "child.mcap", writer_process=True)
    inline, child = (tmp_path / "inline.mcap").read_bytes(), (tmp_path / "child.mcap").read_bytes()
    assert len(inline) > 500_000  # the picture (JPEG of noise) is in it
    assert child == inline


def test_the_tick_loop_thread_encodes_nothing_when_a_child_writes(tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """With a writer process and no live viewer, no message given by its inputs is encoded in the recorder's
    process: the tick's JSON, events, trajectories and images are the child's work."""

    def refuse(encoding: Encoding, args: tuple[Any, ...]) -> bytes:
        raise AssertionError(f"{encoding} encoded in the tick loop's process")

    monkeypatch.setattr("bt_grasp.recording.writer.encode", refuse)
    _record(tmp_path / "child.mcap", writer_process=True)
    with open(tmp_path / "child.mcap", "rb") as stream:
        topics = [channel.topic for _, channel, _ in make_reader(stream).iter_messages()]
    assert topics.count("/bt/tick") == 8 and {"/camera/color", "/camera/depth", "/motion/trajectory"} <= set(topics)


def test_each_ticks_leaves_are_every_leafs_status_that_tick(tmp_path: Path) -> None:
    """The leaves' statuses are kept between ticks and updated from the node entries written; each tick's
    ``leaves`` must still be every leaf's status in that tick's nodes, also after a reset nobody ticked and
    after the node set changed."""
    _record(tmp_path / "child.mcap", writer_process=True)
    with open(tmp_path / "child.mcap", "rb") as stream:
        ticks = [json.loads(m.data) for _, c, m in make_reader(stream).iter_messages() if c.topic == "/bt/tick"]
    expected = [{n["path"].replace("/", "_"): n["status"] for n in nodes if n["kind"] == "Action"}
                for nodes in _ticks()]
    assert [list(t["leaves"].values()) for t in ticks] == [list(e.values()) for e in expected]
    assert [len(t["leaves"]) for t in ticks] == [2, 2, 2, 2, 2, 3, 3, 3]
    assert ticks[4]["leaves"] == dict(zip(ticks[4]["leaves"], ["IDLE", "IDLE"], strict=True))
    assert ticks[3]["bb_removed"] == ["target"]


def test_json_that_json_cannot_hold_is_made_jsonable_not_an_error() -> None:
    value = {"x": math.nan, "y": [1.0, math.inf], "z": _Opaque(), "n": 2}
    assert json_bytes(value) == encodings.dumps(to_jsonable(value, max_array_elements=1 << 30))
    assert json.loads(json_bytes(value))["x"] == "nan"
    assert json_bytes({"a": [1, 2.5, "s", None, True]}) == b'{"a":[1,2.5,"s",null,true]}'
    assert encode(Encoding.JSON, ({"k": 1},)) == b'{"k":1}'


def test_a_batch_cut_short_inside_an_out_of_band_buffer_is_dropped_whole(tmp_path: Path) -> None:
    """A parent killed while the feeder wrote an image leaves a batch without its last bytes: the child must
    drop that batch (and finish the file with the ones before), not unpickle a partial picture."""
    import io
    import pickle

    image = np.arange(200_000, dtype=np.uint8)
    buffers: list[pickle.PickleBuffer] = []
    data = pickle.dumps([("m", image)], protocol=5, buffer_callback=lambda b: bool(buffers.append(b)))
    raw = buffers[0].raw()
    whole = (writer_process._FRAME.pack(len(data), 1) + writer_process._BUFFER_SIZE.pack(raw.nbytes) + data
             + bytes(raw))
    batch = writer_process._read_batch(io.BytesIO(whole))
    assert batch is not None and np.array_equal(batch[0][1], image)
    for cut in (1, writer_process._FRAME.size + 3, len(whole) - raw.nbytes - 1, len(whole) - 1):
        assert writer_process._read_batch(io.BytesIO(whole[:cut])) is None, cut
