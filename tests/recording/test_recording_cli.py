"""`bt-grasp replay`: outputs of each view, JSON keys, and exit code 2 with one sentence for bad logs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import pytest
from recording_helpers import run_cli

BAD_LOGS = Path(__file__).parents[1] / "data" / "bad_logs"


def test_summary_of_a_failed_run_exits_0(failed_run, capsys):
    path, _ = failed_run
    code, out, err = run_cli(["replay", str(path)], capsys)
    assert code == 0, err
    for expected in ("pick.xml", "table.yaml", "FAILURE", "grasp failed", "Grasp", "7 (ticks 1..7)",
                     "retries", "Grasp: 2", "truncated", "status changes"):
        assert expected in out
    lines = out.splitlines()
    tick7 = next(line for line in lines if line.strip().startswith("7 "))
    assert "Pick FAIL" in tick7 and "Grasp FAIL" in tick7


def test_json_summary_keys(failed_run, capsys):
    code, out, _ = run_cli(["replay", str(failed_run[0]), "--json"], capsys)
    assert code == 0
    summary = json.loads(out)
    for key in ("ticks", "truncated", "success", "reason", "failed_leaf", "topics", "faults"):
        assert key in summary
    assert summary["ticks"] == 7 and summary["truncated"] is False and summary["success"] is False
    assert summary["failed_leaf"] == "Grasp" and summary["reason"] == "grasp failed"
    assert summary["topics"]["/bt/tick"] == 7 and summary["topics"]["/camera/color"] == 2
    assert [f["tick"] for f in summary["faults"]] == [3, 5, 7]
    assert summary["retries_per_leaf"] == {"Pick/RetryGrasp/Grasp": 2}  # by path, the node's one name


def test_tick_view(ok_run, capsys):
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--tick", "3"], capsys)
    assert code == 0
    assert "at tick 3" in out
    grasp = next(line for line in out.splitlines() if "Grasp (Scripted)" in line)
    assert "FAILURE" in grasp and "slipped" in grasp and "attempt 1 failed" in grasp
    assert "Lift (Scripted) IDLE" in out
    assert "blackboard" in out and "attempt" in out and "gripper width (m)" in out
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--tick", "3", "--json"], capsys)
    view = json.loads(out)
    assert view["tick"] == 3 and view["blackboard"]["attempt"] == 1
    assert view["tree"]["name"] == "Pick" and view["tree"]["children"][1]["children"][0]["status"] == "FAILURE"
    assert len(view["robot"]["position"]) == 6


def test_tick_out_of_range_is_bad_input(ok_run, capsys):
    code, _, err = run_cli(["replay", str(ok_run[0]), "--tick", "99"], capsys)
    assert code == 2 and "tick 99 is not in ok.mcap (ticks 1..7)" in err


def test_failures_view_shows_what_ran_next(ok_run, capsys):
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--failures", "--json"], capsys)
    assert code == 0
    failures = json.loads(out)
    assert len(failures) == 1
    f = failures[0]
    assert (f["tick"], f["name"], f["reason"]) == (3, "Grasp", "slipped")
    assert [(c["name"], c["new"], c["tick"]) for c in f["recovery"]][:3] == [
        ("Grasp", "RUNNING", 4), ("Grasp", "SUCCESS", 5), ("Lift", "RUNNING", 5)]
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--failures"], capsys)
    flat = " ".join(out.split())  # the table folds long paths at the terminal's width
    assert "slipped" in flat and "Pick/RetryGrasp/Grasp" in flat and "(tick 4) RUN" in out


def test_leaf_history(failed_run, capsys):
    code, out, _ = run_cli(["replay", str(failed_run[0]), "--leaf", "Grasp", "--json"], capsys)
    history = json.loads(out)
    assert [h["status"] for h in history] == ["IDLE", "RUNNING", "FAILURE", "RUNNING", "FAILURE", "RUNNING",
                                              "FAILURE"]
    code, out, _ = run_cli(["replay", str(failed_run[0]), "--leaf", "Grasp"], capsys)
    assert code == 0 and "history of Grasp" in out and out.count("slipped") == 3
    code, _, err = run_cli(["replay", str(failed_run[0]), "--leaf", "Nope"], capsys)
    assert code == 2 and "no node named 'Nope'" in err and "Grasp" in err


def test_topic_as_json_lines(ok_run, capsys):
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--topic", "/bt/events"], capsys)
    assert code == 0
    lines = [json.loads(line) for line in out.splitlines()]
    assert len(lines) == 1 and lines[0]["message"]["kind"] == "failure"
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--topic", "/camera/color"], capsys)
    images = [json.loads(line) for line in out.splitlines()]
    assert len(images) == 2 and images[0]["message"]["format"] == "jpeg"
    assert images[0]["message"]["data"]["__bytes__"] > 0
    code, _, err = run_cli(["replay", str(ok_run[0]), "--topic", "/nope"], capsys)
    assert code == 2 and "no topic '/nope'" in err


def test_export_frames(ok_run, tmp_path, capsys):
    out_dir = tmp_path / "frames"
    code, out, _ = run_cli(["replay", str(ok_run[0]), "--export-frames", str(out_dir)], capsys)
    assert code == 0 and "wrote 4 frames" in out
    files = sorted(p.name for p in out_dir.iterdir())
    assert files == ["color_00000_tick000001.png", "color_00001_tick000006.png",
                     "depth_00000_tick000001.png", "depth_00001_tick000006.png"]
    depth = cv2.imread(str(out_dir / "depth_00001_tick000006.png"), cv2.IMREAD_UNCHANGED)
    assert depth.dtype.name == "uint16" and depth[5, 5] == 560 and depth[0, 0] == 0
    color = cv2.imread(str(out_dir / "color_00000_tick000001.png"), cv2.IMREAD_COLOR)
    assert color.shape == (24, 32, 3)


@pytest.mark.parametrize("name", ["empty.mcap", "text.mcap", "image.mcap", "header10.mcap",
                                  "not_bt_grasp.mcap", "directory.mcap", "missing.mcap"])
def test_bad_logs_exit_2_with_one_sentence(name, capsys):
    path = BAD_LOGS / name
    code, out, err = run_cli(["replay", str(path)], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"bt-grasp: error: {path}: ")
    assert "Traceback" not in err and out == ""


def test_bad_log_through_the_real_entry_point():
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(BAD_LOGS / "text.mcap")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip() == (f"bt-grasp: error: {BAD_LOGS / 'text.mcap'}: is not an MCAP file "
                                   "(it does not start with the MCAP magic bytes)")
