"""Writer -> reader round trip of every topic, Foxglove schema names, and change-only writing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from bt_grasp.recording import RunRecorder, open_log, topics

FOXGLOVE = {
    "/camera/color": "foxglove.CompressedImage",
    "/camera/depth": "foxglove.RawImage",
    "/perception/points": "foxglove.PointCloud",
    "/tf": "foxglove.FrameTransforms",
    "/perception/detections": "foxglove.SceneUpdate",
    "/perception/grasps": "foxglove.SceneUpdate",
    "/log": "foxglove.Log",
}


def test_every_topic_round_trips(ok_run):
    path, written = ok_run
    run = open_log(path)
    assert not run.truncated and run.indexed
    assert run.ticks_recovered == written["n_ticks"] == 7
    assert [t.tick for t in run.ticks] == list(range(1, 8))
    assert run.metadata["seed"] == "7" and run.metadata["tree_file"] == "pick.xml"
    assert run.metadata["log_format"] == topics.LOG_FORMAT_VERSION
    assert run.attachments == {"pick.xml": b"<root BTCPP_format=\"4\"/>", "table.yaml": b"objects: []\n"}
    assert run.result == written["result"]
    assert run.structures[0].root["name"] == "Pick"
    assert {n.name for n in run.nodes.values()} == {"Pick", "Detect", "RetryGrasp", "Grasp", "Lift"}
    assert [e["kind"] for e in run.events] == ["failure"]
    assert run.events[0]["payload"] == {"leaf": "Grasp", "reason": "slipped"}
    assert run.faults[0]["tick"] == 3 and run.faults[0]["fault"]["name"] == "slip"
    assert run.logs[0]["level"] == "INFO" and run.logs[0]["message"] == "detected cube"
    assert run.trajectories[0]["kind"] == "planned" and len(run.trajectories[0]["q_rad"]) == 3
    # every topic is there with the right count
    assert run.topics["/bt/tick"] == 7 and run.topics["/robot/joint_state"] == 7
    assert run.topics["/tf"] == 8  # one static camera transform + one TCP per tick
    assert run.topics["/camera/color"] == run.topics["/camera/depth"] == 2
    # states and blackboard accumulate to what was written
    for i, nodes in enumerate(written["ticks"], start=1):
        states = run.states_at(i)
        assert {n["uid"]: n["status"] for n in nodes} == {u: s.status for u, s in states.items()}
    final_bb = run.blackboard_at(7)
    assert final_bb["attempt"] == 2 and final_bb["target"] == "cube"
    assert final_bb["big_cloud"]["__ndarray__"]["shape"] == [500, 3]
    robot = run.robot_at(7)
    assert robot is not None and len(robot["position"]) == 6
    assert robot["tcp_xyz_m"] == [0.4, 0.0, 0.3 + 0.007]


def test_images_decode(ok_run):
    run = open_log(ok_run[0])
    images = list(run.images())
    colors = [i for i in images if i.kind == "color"]
    depths = [i for i in images if i.kind == "depth"]
    assert len(colors) == len(depths) == 2
    assert colors[0].pixels.shape == (24, 32, 3)
    assert abs(int(colors[0].pixels[6, 6, 0]) - 200) < 12  # JPEG, so approximately
    assert depths[0].pixels.dtype == np.uint16 and depths[0].pixels[0, 0] == 0  # NaN -> invalid
    assert depths[0].pixels[5, 5] == 510  # 0.51 m in mm


def test_plain_mcap_reader_sees_foxglove_schemas(ok_run):
    with ok_run[0].open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None
        names = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
        for topic, schema in FOXGLOVE.items():
            assert names[topic] == schema
        for topic in topics.JSON_TOPICS:
            channel = next(c for c in summary.channels.values() if c.topic == topic)
            assert channel.message_encoding == "json"
            assert summary.schemas[channel.schema_id].encoding == "jsonschema"
        decoded = {m.channel.topic: m.decoded_message
                   for m in reader.iter_decoded_messages(topics=list(FOXGLOVE))}
        assert decoded["/camera/color"].format == "jpeg"
        assert decoded["/camera/depth"].encoding == "16UC1"
        assert decoded["/perception/points"].point_stride == 12
        assert decoded["/tf"].transforms[0].parent_frame_id == "base_link"
        assert decoded["/perception/detections"].entities[0].cubes[0].size.x == 0.05
        assert len(decoded["/perception/grasps"].entities[0].arrows) == 3
        # log_time = publish_time = the run's start (wall clock, in the metadata) + simulated time
        origin = int(next(iter(reader.iter_metadata())).metadata["time_origin_ns"])
        assert origin > 1_500_000_000 * 10**9
        ticks = [m for _, _, m in reader.iter_messages(topics=["/bt/tick"])]
        assert [m.log_time - origin for m in ticks] == [i * 10_000_000 for i in range(1, 8)]
        assert all(m.publish_time == m.log_time for m in ticks)
        # the messages' own stamps are on the same time line (Foxglove matches images and transforms by them)
        stamp = decoded["/camera/color"].timestamp
        assert stamp.seconds * 10**9 + stamp.nanos >= origin


def _raw_ticks(path: Path) -> list[dict]:
    with path.open("rb") as f:
        return [json.loads(m.data) for _, _, m in make_reader(f).iter_messages(topics=["/bt/tick"])]


def test_only_changed_nodes_and_blackboard_entries_are_written(ok_run):
    ticks = _raw_ticks(ok_run[0])
    first = ticks[0]
    assert len(first["nodes"]) == 5  # everything, the first time
    assert all("path" in n for n in first["nodes"])
    assert set(first["bb"]) == {"big_cloud", "target", "attempt", "T_base_object"}
    # tick 4: Detect, Lift unchanged and not ticked -> absent; Pick, RetryGrasp ticked -> present
    fourth = {n["uid"]: n for n in ticks[3]["nodes"]}
    names = {1: "Pick", 2: "Detect", 3: "RetryGrasp", 4: "Grasp", 5: "Lift"}
    assert {names[u] for u in fourth} == {"Pick", "RetryGrasp", "Grasp"}
    assert all("path" not in n for n in fourth.values())
    # blackboard: only 'attempt' changed between tick 2 and 3 (3 // 3 == 1)
    assert ticks[2]["bb"] == {"attempt": 1}
    assert "bb" not in ticks[3]


def test_blackboard_removal_and_conversions(tmp_path):
    from dataclasses import dataclass
    from enum import Enum

    class Mode(Enum):
        FAST = 1

    @dataclass
    class Grasp:
        width_m: float
        mode: Mode

    path = tmp_path / "bb.mcap"
    with RunRecorder(path, metadata={"seed": "1"}) as rec:
        rec.write_tick(0, 0, [], {"g": Grasp(0.04, Mode.FAST), "x": float("nan"), "p": Path("/a"), "s": {2, 1}})
        rec.write_tick(1, 1, [], {"g": Grasp(0.04, Mode.FAST)})
        rec.flush_tick()
    run = open_log(path)
    assert run.ticks[0].bb == {"g": {"__type__": "Grasp", "width_m": 0.04, "mode": "FAST"}, "x": "nan",
                               "p": "/a", "s": [1, 2]}
    assert run.ticks[1].bb == {} and set(run.ticks[1].bb_removed) == {"x", "p", "s"}
    assert run.blackboard_at(1) == {"g": {"__type__": "Grasp", "width_m": 0.04, "mode": "FAST"}}


def test_tree_structure_is_written_again_only_when_it_changes(tmp_path):
    path = tmp_path / "tree.mcap"
    a = {"uid": 1, "type": "Sequence", "name": "A", "path": "A", "kind": "control", "attributes": {},
         "children": []}
    with RunRecorder(path, metadata={}) as rec:
        assert rec.write_tree_structure(0, a)
        assert not rec.write_tree_structure(1, dict(a))
        rec.write_tick(1, 10, [], {})
        assert rec.write_tree_structure(20, {**a, "name": "B"})
    run = open_log(path)
    assert [s.root["name"] for s in run.structures] == ["A", "B"]
    assert run.structures[1].tick == 1


def test_exception_inside_the_block_still_finishes_the_file(tmp_path):
    path = tmp_path / "boom.mcap"
    try:
        with RunRecorder(path, metadata={"seed": "1"}) as rec:
            rec.write_tick(0, 0, [], {})
            raise RuntimeError("planner exploded")
    except RuntimeError:
        pass
    run = open_log(path)
    assert not run.truncated
    assert run.events[-1]["kind"] == "aborted"
    assert run.events[-1]["payload"] == {"exception": "RuntimeError", "message": "planner exploded"}
