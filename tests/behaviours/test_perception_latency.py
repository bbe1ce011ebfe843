"""Perception latency paid in simulated time (issue 45), tick by tick with stand-ins: a capture's detections reach
the tree exactly the cell's declared latency after the frame's timestamp, whatever they say, for every perceiving
leaf; with none, in the tick the frame was taken (as before latency was paid).

Ticks are 10 ms of simulated time; the camera stamps each frame with the clock, as the simulated D435 does.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from behaviour_fakes import FakeRobot, fake_cell
from perception_synth import DEFAULT_T_BASE_CAMERA, INTRINSICS, Box, render

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.cell import Cell
from bt_grasp.clock import ManualClock
from bt_grasp.errors import ConfigError
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string

REPO = Path(__file__).resolve().parents[2]
TICK_S = 0.01
BOX = render([Box((0.45, 0.0), (0.05, 0.05, 0.05))])
EMPTY = render([])


class StampingCamera:
    """Returns its frame stamped with the clock's time at capture, and counts captures."""

    mount = Mount.EYE_TO_HAND
    intrinsics: CameraIntrinsics = INTRINSICS

    def __init__(self, frame: RGBDFrame, clock: ManualClock) -> None:
        self.frame, self.clock, self.captures = frame, clock, 0

    def capture(self) -> RGBDFrame:
        self.captures += 1
        return dataclasses.replace(self.frame, stamp_ns=self.clock.now_ns())


class FixedCalibration:
    mount = "eye-to-hand"
    tool_link = "tool0"

    def T_base_camera_at(self, T_base_tool: np.ndarray | None = None) -> np.ndarray:
        return DEFAULT_T_BASE_CAMERA


def _tree(body: str, frame: RGBDFrame, latency_s: float) -> tuple[LoadedTree, Cell, ManualClock]:
    clock = ManualClock()
    cell = fake_cell(FakeRobot(), clock)
    cell.camera = StampingCamera(frame, clock)
    cell.calibration = FixedCalibration()
    cell.perception_latency_s = latency_s
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="T">{body}</BehaviorTree></root>'
    tree = load_tree_from_string(xml, robot_registry(), clock=clock)
    for node in tree.nodes():
        node.setup(cell=cell)
    return tree, cell, clock


def _tick_until_done(tree: LoadedTree, clock: ManualClock, key: str | None = None) -> list[tuple[str, bool]]:
    """(status, whether ``key`` is on the blackboard) per tick until the tree completes."""
    seen = []
    for _ in range(200):
        status = tree.tick().value
        seen.append((status, key is not None and tree.root_blackboard.get(key, None) is not None))
        if status != "RUNNING":
            return seen
        clock.advance_s(TICK_S)
    raise AssertionError("the tree never completed")


@pytest.mark.parametrize("latency_s", [0.0, 0.03, 0.1, 0.105])
def test_perceive_hands_its_detections_over_exactly_the_latency_after_the_frame(latency_s: float) -> None:
    tree, cell, clock = _tree('<Perceive color="red" target="{target}"/>', BOX, latency_s)
    seen = _tick_until_done(tree, clock, "target")
    # the frame is taken at the first tick (t = 0); the tree sees the target at the first tick at or after
    # t = latency: every tick before is RUNNING with nothing on the blackboard
    ready_tick = math.ceil(round(latency_s / TICK_S, 6))
    assert seen == [("RUNNING", False)] * ready_tick + [("SUCCESS", True)]
    assert clock.now_ns() == ready_tick * 10_000_000 and clock.now_ns() >= round(latency_s * 1e9)
    assert cell.camera.captures == 1  # type: ignore[attr-defined]


def test_no_detection_is_also_news_that_arrives_after_the_latency() -> None:
    tree, _, clock = _tree('<Perceive color="red" target="{target}"/>', EMPTY, 0.1)
    seen = _tick_until_done(tree, clock)
    assert [s for s, _ in seen] == ["RUNNING"] * 10 + ["FAILURE"]
    assert tree.root_blackboard.get("failure_reason") == "NO_DETECTION"


@pytest.mark.parametrize("body", ['<PerceiveAll objects="{target}"/>', '<ObjectVisible color="red"/>'])
def test_every_perceiving_leaf_pays_the_latency(body: str) -> None:
    tree, _, clock = _tree(body, BOX, 0.05)
    seen = _tick_until_done(tree, clock, "target" if "PerceiveAll" in body else None)
    assert [s for s, _ in seen] == ["RUNNING"] * 5 + ["SUCCESS"]
    if "PerceiveAll" in body:
        assert [on for _, on in seen] == [False] * 5 + [True]


def test_a_halted_perception_forgets_its_capture() -> None:
    tree, cell, clock = _tree('<Perceive color="red" target="{target}"/>', BOX, 0.1)
    assert tree.tick().value == "RUNNING"
    clock.advance_s(0.05)
    tree.halt()
    clock.advance_s(0.05)
    # a new attempt takes a new frame and waits its own full latency (the old capture is not handed over)
    seen = _tick_until_done(tree, clock, "target")
    assert [s for s, _ in seen] == ["RUNNING"] * 10 + ["SUCCESS"]
    assert cell.camera.captures == 2  # type: ignore[attr-defined]


def test_follow_target_adds_each_measurement_stamped_with_its_frame_when_it_arrives() -> None:
    body = '<FollowTarget color="red" standoff="0.15" converged_time="-1" rate="15" track="{track}"/>'
    tree, cell, clock = _tree(body, render([Box((0.5, 0.05), (0.05, 0.05, 0.05), 0.2)], noise_m=0.001, seed=1), 0.1)
    camera = cell.camera
    taken: list[float] = []
    capture = camera.capture

    def logged_capture() -> RGBDFrame:
        frame = capture()
        taken.append(frame.stamp_ns * 1e-9)
        return frame

    camera.capture = logged_capture  # type: ignore[method-assign]
    for _ in range(60):
        assert tree.tick().value == "RUNNING"
        track = tree.root_blackboard.get("track", None)
        arrived = [t for t in taken if t + 0.1 <= clock.now_s() + 1e-9]
        # the track holds exactly the frames whose latency has passed, each stamped with its frame's time
        assert [t for t, _ in track.samples] == pytest.approx(arrived) if track is not None else arrived == []
        clock.advance_s(TICK_S)
    assert taken[:3] == pytest.approx([0.0, 0.10, 0.17])  # the full perception, then measurements at 15 Hz


def test_a_scene_may_declare_its_latency_and_the_default_is_the_packages() -> None:
    from bt_grasp.defaults import DEFAULT_PERCEPTION_LATENCY_S

    assert Scene().latency_s == DEFAULT_PERCEPTION_LATENCY_S == 0.100
    assert Scene(version=2, perception_latency_s=0.0).latency_s == 0.0


def test_a_version_1_scene_with_a_latency_is_told_to_say_version_2(tmp_path: Path) -> None:
    path = tmp_path / "v1.yaml"
    path.write_text("name: v1\nperception_latency_s: 0.05\n")
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    assert "perception_latency_s" in str(info.value) and "version: 2" in str(info.value)
    path.write_text("version: 2\nname: v2\nperception_latency_s: -0.05\n")
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    assert ":3" in str(info.value) and "perception_latency_s" in str(info.value)


def test_a_log_made_before_latency_was_paid_is_resimulated_with_none() -> None:
    from bt_grasp.cli.resim import _recorded_latency
    from bt_grasp.errors import LogFileError

    log = Path("old.mcap")
    assert _recorded_latency(log, {"seed": "3"}) == 0.0
    assert _recorded_latency(log, {"perception_latency_s": "0.1"}) == 0.1
    for bad in ("-1", "nan", "soon", "9"):
        with pytest.raises(LogFileError):
            _recorded_latency(log, {"perception_latency_s": bad})
