"""The run report says what happened (issue 24): one test per defect, each failing on the code before.

A hand-written log (the real writer and reader, no simulator) whose tree is ``root`` (Sequence) over leaves
``A`` and ``B``: A runs at tick 1 and succeeds at tick 2, then waits, not ticked, while B runs ticks 3-9 and
succeeds at tick 10, which ends the run (the root's reset shows every node IDLE in the last record, as a
real run's does). A fault fires at tick 4. The camera takes a frame at tick 2 with one detected box and
another at tick 8 with no detection.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bt_grasp.geometry import make_T
from bt_grasp.recording import BoxMarker, report, report_figures
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder

TICK_NS = 10_000_000
STRUCTURE = {"uid": 1, "type": "Sequence", "name": "root", "path": "root", "kind": "Control", "attributes": {},
             "children": [
                 {"uid": 2, "type": "A", "name": "A", "path": "A::2", "kind": "Action", "attributes": {},
                  "children": []},
                 {"uid": 3, "type": "B", "name": "B", "path": "B::3", "kind": "Action", "attributes": {},
                  "children": []}]}


def _node(uid: int, status: str, ticked: bool) -> dict[str, Any]:
    info = {1: ("root", "Sequence", "Control"), 2: ("A::2", "A", "Action"), 3: ("B::3", "B", "Action")}[uid]
    return {"uid": uid, "path": info[0], "name": info[1], "type": info[1], "kind": info[2], "status": status,
            "ticked": ticked, "feedback": "", "failure_reason": None}


def _statuses(tick: int) -> list[dict[str, Any]]:
    """What the runner records: what each node returned when ticked, else its status as it stands."""
    if tick == 1:
        return [_node(1, "RUNNING", True), _node(2, "RUNNING", True), _node(3, "IDLE", False)]
    if tick == 2:
        return [_node(1, "RUNNING", True), _node(2, "SUCCESS", True), _node(3, "RUNNING", False)]
    if tick < 10:
        return [_node(1, "RUNNING", True), _node(2, "SUCCESS", False), _node(3, "RUNNING", True)]
    return [_node(1, "SUCCESS", True), _node(2, "IDLE", False), _node(3, "SUCCESS", True)]


@pytest.fixture
def log_path(tmp_path: Path) -> Path:
    path = tmp_path / "run.mcap"
    rgb = np.full((48, 64, 3), 90, dtype=np.uint8)
    with RunRecorder(path, metadata={"seed": "0", "tree_file": "t.xml"}, handle_signals=False,
                     time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_tree_structure(0, STRUCTURE)
        for tick in range(1, 11):
            stamp = (tick - 1) * TICK_NS
            if tick == 2:
                rec.write_color_image(stamp, rgb, "camera_color_optical_frame")
                rec.write_markers(stamp, [BoxMarker("det0", make_T(np.eye(3), [0.5, 0.0, 0.05]), (0.05, 0.05, 0.05),
                                                    label="red_box")])
            if tick == 8:
                rec.write_color_image(stamp, rgb, "camera_color_optical_frame")
            if tick == 4:
                rec.write_fault(stamp, tick, {"kind": "frame_drop", "label": "frame_drop@B#1"})
            rec.write_tick(tick, stamp, _statuses(tick), {})
        rec.write_result(9 * TICK_NS, {"success": True, "reason": None, "failed_leaf": None})
    return path


class Spy:
    def __init__(self, real: Any) -> None:
        self.real = real
        self.calls: list[tuple[tuple[Any, ...], dict[str, Any]]] = []

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        self.calls.append((args, kwargs))
        return self.real(*args, **kwargs)


def test_a_gantt_bar_ends_when_the_leaf_stops(log_path: Path, tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    gantt = Spy(report_figures.gantt)
    monkeypatch.setattr(report_figures, "gantt", gantt)
    report.build_report(open_log(log_path), tmp_path / "r.html")
    (rows, bars, *_), _ = gantt.calls[0]
    spans = sorted((rows.index(b.row), b.status, round(b.start_s, 3), round(b.start_s + b.length_s, 3))
                   for b in bars)
    # A: RUNNING for tick 1, SUCCESS for tick 2 only (before: SUCCESS painted on to tick 10, A's reset)
    assert spans == [(0, "RUNNING", 0.0, 0.01), (0, "SUCCESS", 0.01, 0.02),
                     (1, "RUNNING", 0.02, 0.09), (1, "SUCCESS", 0.09, 0.1)], spans
    assert rows == ["A::2", "B::3"]  # by path, the leaves' one name


def test_the_end_tree_shows_how_each_node_ended_not_the_reset(log_path: Path, tmp_path: Path) -> None:
    page = (report.build_report(open_log(log_path), tmp_path / "r.html").html_path).read_text()
    tree = page[page.index("The tree at the end"):]
    statuses = dict(re.findall(r'<span class="node">([^<]*)</span>.*?class="st st-(\w+)"', tree))
    # before: A IDLE (the root's reset after it succeeded), though A ran and succeeded
    assert statuses == {"root": "SUCCESS", "A": "SUCCESS", "B": "SUCCESS"}, statuses


def test_injected_faults_are_marked_on_the_timeline(log_path: Path, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    gantt = Spy(report_figures.gantt)
    monkeypatch.setattr(report_figures, "gantt", gantt)
    report.build_report(open_log(log_path), tmp_path / "r.html")
    args, kwargs = gantt.calls[0]
    faults = kwargs.get("faults", args[3] if len(args) > 3 else ())
    assert [(round(t, 3), text) for t, text in faults] == [(0.03, "frame_drop@B#1")]  # before: not passed at all
    # and the figure draws it: the legend names it
    png_with = report_figures.gantt(["A::2"], [], [], faults)
    png_without = report_figures.gantt(["A::2"], [], [], [])
    assert png_with != png_without


def test_a_detection_box_is_drawn_only_on_the_frame_it_was_detected_in(log_path: Path, tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    frames = Spy(report_figures.frame_with_boxes)
    monkeypatch.setattr(report_figures, "frame_with_boxes", frames)
    report.build_report(open_log(log_path), tmp_path / "r.html")
    boxes = [[label for _T, _size, label in args[3]] for args, _ in frames.calls]
    # before: the tick-8 frame, taken with nothing detected, still carried tick 2's box
    assert boxes == [["red_box"], []], boxes
