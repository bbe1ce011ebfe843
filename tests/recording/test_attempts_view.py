"""Attempts in `replay --attempts` and the run report (issue 46): each attempt with where it was made, how it
ended and what earlier attempts ruled out before it; one that repeats a failed attempt is marked."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from recording_helpers import DT_NS, run_cli

from bt_grasp.behaviours.attempts import Attempt, AttemptKind, Exclusion, GraspFamily, ObjectSeen, Outcome
from bt_grasp.geometry import make_T
from bt_grasp.recording.writer import RunRecorder

CAN = ObjectSeen((0.45, 0.05, 0.06), (0.066, 0.066, 0.12), 0.0, "can", "can")
TOP_DOWN = np.diag([1.0, -1.0, -1.0])  # tool z down


def _grasp(index: int, x: float, outcome: Outcome, reason: str | None, excluded: tuple[Exclusion, ...] = ()
           ) -> Attempt:
    return Attempt(index=index, kind=AttemptKind.GRASP, leaf="Pick/PlanGrasp", tick=10 * index, object=CAN,
                   T_base_tcp=make_T(TOP_DOWN, [x, 0.05, 0.08]), family=GraspFamily.TOP, approach="top-down",
                   outcome=outcome, reason=reason, end_tick=10 * index + 5, end_leaf="Pick/Grasp", width_m=0.066,
                   moved=True, excluded=excluded)


def _record(path: Path, attempts: list[Attempt]) -> None:
    with RunRecorder(path, metadata={"seed": "3", "tree_file": "pick.xml", "scene_file": "table.yaml"},
                     handle_signals=False) as rec:
        rec.write_tree_structure(0, {"uid": 1, "type": "Action", "name": "Pick", "path": "Pick", "kind": "Action",
                                     "attributes": {}, "children": []})
        for tick in range(1, 41):
            rec.write_tick(tick, tick * DT_NS, [{"uid": 1, "path": "Pick", "type": "Action", "name": "Pick",
                                                 "kind": "Action", "status": "RUNNING", "feedback": "",
                                                 "failure_reason": None, "ticked": True}], {}, None)
            for a in attempts:
                if a.end_tick == tick:
                    rec.write_attempt(tick * DT_NS, a.to_json())
            rec.flush_tick()
        rec.write_result(40 * DT_NS, {"success": False, "reason": "GRASP_EMPTY", "failed_leaf": "Grasp",
                                      "ticks": 40, "sim_time_s": 0.4})


@pytest.fixture
def attempts_log(tmp_path: Path) -> Path:
    path = tmp_path / "attempts.mcap"
    first = _grasp(1, 0.450, Outcome.FAILED, "GRASP_EMPTY")
    ruled_out = (Exclusion("candidate 0", 1, "repeat", "repeats grasp #1 (GRASP_EMPTY)"),)
    second = _grasp(2, 0.470, Outcome.STALLED, "TRACKING_ERROR", excluded=ruled_out)
    third = _grasp(3, 0.452, Outcome.FAILED, "GRASP_EMPTY")  # 2 mm from the first, same family: a repeat
    _record(path, [first, second, third])
    return path


def test_replay_attempts_lists_each_attempt_and_marks_a_repeat(attempts_log, capsys):
    code, out, err = run_cli(["replay", str(attempts_log), "--attempts", "--json"], capsys)
    assert code == 0, err
    rows = json.loads(out)
    assert [(r["index"], r["kind"], r["family"]) for r in rows] == [(1, "grasp", "top"), (2, "grasp", "top"),
                                                                    (3, "grasp", "top")]
    assert [r["outcome"] for r in rows] == ["FAILED GRASP_EMPTY", "STALLED TRACKING_ERROR", "FAILED GRASP_EMPTY"]
    assert rows[1]["excluded"] == ["candidate 0: repeats grasp #1 (GRASP_EMPTY) (attempt #1, repeat)"]
    assert [r["repeats"] for r in rows] == [False, False, True]
    assert rows[0]["object"] == "can at (0.450, 0.050)" and rows[0]["where"].startswith("tool 0.450;0.050;0.080")
    code, out, err = run_cli(["replay", str(attempts_log), "--attempts"], capsys)
    assert code == 0, err
    assert "REPEAT" in out and "3 attempt(s); repeating a failed one: [3]" in out


def test_a_log_without_attempts_says_so(make_run, capsys):
    path, _ = make_run("old.mcap")
    code, out, _ = run_cli(["replay", str(path), "--attempts"], capsys)
    assert code == 0 and "no grasp or placement attempt recorded" in out


def test_the_run_report_has_the_attempts(attempts_log, tmp_path, capsys):
    html_path = tmp_path / "report" / "report.html"
    code, _, err = run_cli(["replay", str(attempts_log), "--report", str(html_path)], capsys)
    assert code == 0, err
    page = html_path.read_text()
    assert "Attempts (grasps and placements)" in page
    assert page.count("<b>REPEAT</b>") == 1 and "TRACKING_ERROR" in page
    assert "repeats grasp #1 (GRASP_EMPTY) (attempt #1, repeat)" in page


def test_the_foxglove_layout_shows_the_attempts_channel() -> None:
    layout = Path(__file__).parents[2] / "bt_grasp" / "foxglove" / "layouts" / "bt_grasp.layout.json"
    configs = json.loads(layout.read_text())["configById"]
    assert any(c.get("topicPath") == "/bt/attempts" for c in configs.values())


def test_bench_attempts_counts_the_repeat(attempts_log: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.main import main

    assert main(["bench", "attempts", str(attempts_log), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    counts = (summary["episodes"], summary["failed"], summary["repeats"], summary["episodes_with_repeats"])
    assert counts == (1, 1, 1, 1)
    assert summary["attempts_per_failed_episode"] == {"3": 1}
    [entry] = summary["logs"]
    assert entry["repeats"] == [[1, 3]] and entry["rebuilt"] is False
    assert main(["bench", "attempts", str(attempts_log)]) == 0
    out = capsys.readouterr().out
    assert "1 repeated attempt(s) in 1 episode(s)" in out and "#3 repeats #1" in out
