"""`bt-grasp replay LOG` marks injected faults on its text timeline (issue 24): each fault's name, kind, the node or
object it hit and what it did, on its own row at the tick it fired; `--tick N` lists the faults of that tick. On main
as it was the run report's Gantt chart marked them, but the terminal's timeline showed status changes only (the
summary said "faults fired: 2", nothing said which, where or when).

A hand-written log (the real writer and reader, no simulator): ``pick`` (Sequence) over ``Perceive`` and ``Grasp``;
a frame drop armed on Perceive fires at tick 3 (Perceive fails there), an object nudge fires at tick 5, a tick in
which no node changed status.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli.main import main
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder

TICK_NS = 10_000_000
NODES = {1: ("pick", "pick", "Sequence", "Control"), 2: ("pick/Perceive", "Perceive", "Perceive", "Action"),
         3: ("pick/Grasp", "Grasp", "Grasp", "Action")}
STRUCTURE = {"uid": 1, "type": "Sequence", "name": "pick", "path": "pick", "kind": "Control", "attributes": {},
             "children": [{"uid": uid, "type": NODES[uid][2], "name": NODES[uid][1], "path": NODES[uid][0],
                           "kind": "Action", "attributes": {}, "children": []} for uid in (2, 3)]}
# what the injector records (bt_grasp.faults.injector: Fault.to_dict() plus leaf, armed tick, firing, details)
FRAME_DROP = {"kind": "frame_drop", "label": "frame_drop@Perceive#1", "trigger": {"on_leaf": "Perceive", "nth": 1},
              "count": 1, "params": {"frames": 1}, "leaf": "Perceive", "armed_tick": 2, "firing": 1,
              "details": {"effect": "no frame"}}
NUDGE = {"kind": "object_nudge", "label": "nudge", "trigger": {"at_tick": 5}, "count": 1,
         "params": {"object": "red_box", "distance_m": 0.02}, "leaf": None, "armed_tick": 5, "firing": 2,
         "details": {"effect": "pushed red_box 20 mm"}}
# per tick: Perceive RUNNING 1-2, FAILURE at 3 (the dropped frame), RUNNING again 4-6 (a retry), SUCCESS 7
PERCEIVE = {1: "RUNNING", 2: "RUNNING", 3: "FAILURE", 4: "RUNNING", 5: "RUNNING", 6: "RUNNING", 7: "SUCCESS"}


def _node(uid: int, status: str) -> dict[str, Any]:
    path, name, node_type, kind = NODES[uid]
    return {"uid": uid, "path": path, "name": name, "type": node_type, "kind": kind, "status": status,
            "ticked": status != "IDLE", "feedback": "", "failure_reason": "NO_FRAME" if status == "FAILURE" else None}


@pytest.fixture
def log_path(tmp_path: Path) -> Path:
    path = tmp_path / "run.mcap"
    with RunRecorder(path, metadata={"seed": "0", "tree_file": "t.xml"}, handle_signals=False) as rec:
        rec.write_tree_structure(0, STRUCTURE)
        for tick in range(1, 9):
            stamp = (tick - 1) * TICK_NS
            if tick == 3:
                rec.write_fault(stamp, tick, FRAME_DROP)
            if tick == 5:
                rec.write_fault(stamp, tick, NUDGE)
            if tick < 8:
                statuses = [_node(1, "RUNNING"), _node(2, PERCEIVE[tick]), _node(3, "IDLE")]
            else:
                statuses = [_node(1, "SUCCESS"), _node(2, "SUCCESS"), _node(3, "SUCCESS")]
            rec.write_tick(tick, stamp, statuses, {})
        rec.write_result(7 * TICK_NS, {"success": True, "reason": None, "failed_leaf": None})
    return path


def _replay(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    code = main(["replay", *args])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return captured.out


def _rows(out: str) -> list[list[str]]:
    """The timeline's rows as [tick, sim time, text]."""
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("status changes"))
    return [line.rstrip().split(maxsplit=2) for line in lines[start + 2:] if line.strip()]


def test_the_timeline_marks_each_fault_at_its_tick(log_path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "160")
    out = _replay(capsys, str(log_path))
    assert "status changes and injected faults" in out
    rows = _rows(out)
    faults = [row for row in rows if row[2].startswith("FAULT ")]
    assert faults == [
        ["3", "0.020s", "FAULT frame_drop@Perceive#1 (frame_drop) on pick/Perceive: no frame"],  # the node's path
        ["5", "0.040s", "FAULT nudge (object_nudge) on red_box: pushed red_box 20 mm"],  # no leaf: the object
    ]
    ticks = [row[0] for row in rows]
    # the fault's row follows its tick's status changes (Perceive failed in tick 3); tick 5 changed nothing
    assert ticks == ["1", "3", "3", "4", "5", "7", "8"], rows
    assert rows[1][2] == "pick/Perceive FAIL"


def test_max_rows_counts_the_faults_and_says_what_it_left_out(log_path: Path, capsys: pytest.CaptureFixture[str],
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "160")
    out = _replay(capsys, str(log_path), "--max-rows", "3")
    assert [row[0] for row in _rows(out)][:4] == ["1", "3", "3", "…"]  # the last: the line saying what is left
    assert "… 3 more ticks with changes and 1 more faults (--max-rows to show more)" in out


def test_the_tick_view_lists_the_faults_of_that_tick(log_path: Path, capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "160")
    assert "FAULT frame_drop@Perceive#1 (frame_drop) on pick/Perceive: no frame" in _replay(
        capsys, str(log_path), "--tick", "3")
    assert "FAULT" not in _replay(capsys, str(log_path), "--tick", "4")
    view = json.loads(_replay(capsys, str(log_path), "--tick", "5", "--json"))
    assert view["faults"] == [{"tick": 5, "stamp_ns": 40_000_000, "label": "nudge", "kind": "object_nudge",
                               "target": "red_box", "effect": "pushed red_box 20 mm"}]


def test_fault_marks_read_what_the_log_holds(log_path: Path) -> None:
    from bt_grasp.recording.replay import FaultMark, fault_marks

    assert fault_marks(open_log(log_path)) == [
        FaultMark(3, 20_000_000, "frame_drop@Perceive#1", "frame_drop", "pick/Perceive", "no frame"),
        FaultMark(5, 40_000_000, "nudge", "object_nudge", "red_box", "pushed red_box 20 mm"),
    ]
    # markup in a label from the file prints as text
    assert FaultMark(1, 0, "[bold]x[/]", "frame_drop", "", "").text() == "[bold]x[/] (frame_drop)"
