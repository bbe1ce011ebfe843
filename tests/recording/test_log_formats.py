"""Log format versions: today's logs (format 2) and the first format still read; an unknown one is refused
with one sentence naming its version."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_grasp.errors import LogFileError
from bt_grasp.recording import topics
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder

OLD = Path(__file__).resolve().parents[1] / "data" / "old_logs" / "format1.mcap"


def test_a_format_1_log_still_reads_with_simulated_times() -> None:
    log = open_log(OLD)
    assert log.metadata["log_format"] == "1"
    assert log.time_origin_ns == 0
    assert [t.tick for t in log.ticks] == list(range(1, 8))
    assert log.ticks[0].stamp_ns == 10_000_000
    assert log.result is not None
    assert log.robot_at(3) is not None


def test_today_s_log_reads_simulated_times_back(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    with RunRecorder(path, metadata={"seed": "0"}, handle_signals=False, time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_tick(1, 10_000_000, [{"uid": 1, "path": "A", "type": "Action", "name": "A", "kind": "Action",
                                        "status": "RUNNING", "ticked": True}], {},
                       {"q_rad": [0.0] * 6, "gripper_width_m": 0.05})
        rec.write_log(10_000_000, "INFO", "test", "hello")
    log = open_log(path)
    assert log.metadata["log_format"] == topics.LOG_FORMAT_VERSION == "4"
    assert log.time_origin_ns == 1_700_000_000 * 10**9
    assert log.ticks[0].stamp_ns == 10_000_000
    assert log.logs[0]["stamp_ns"] == 10_000_000
    raw = next(log.iter_messages("/bt/tick")).message
    assert raw["leaves"] == {"A": "RUNNING"}  # what Foxglove's State Transitions plots
    assert log.robot_at(1)["gripper_width_m"] == 0.05


def test_an_unknown_format_is_refused_in_one_sentence(tmp_path: Path) -> None:
    path = tmp_path / "future.mcap"
    with RunRecorder(path, metadata={"log_format": "99"}, handle_signals=False) as rec:
        rec.write_log(0, "INFO", "test", "from the future")
    with pytest.raises(LogFileError) as info:
        open_log(path)
    message = str(info.value)
    assert "log format 99" in message and "reads formats 1 and 2 and 3 and 4" in message
    assert message.count(". ") == 0


def test_replay_reports_and_explains_foxglove_for_an_old_log(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]

    def cli(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], capture_output=True, text=True,
                              timeout=120, env={**os.environ, "PYTHONPATH": str(root)})

    html = tmp_path / "report.html"
    made = cli("replay", str(OLD), "--report", str(html), "--report-dir", str(tmp_path / "png"))
    assert made.returncode == 0, made.stdout + made.stderr
    page = html.read_text()
    assert "<script" not in page and "http://" not in page and "https://" not in page  # self-contained
    assert "Leaf statuses over time" in page and "data:image/png;base64," in page
    assert (tmp_path / "png" / "gantt.png").stat().st_size > 1000
    layout = tmp_path / "format1.layout.json"
    told = cli("replay", str(OLD), "--foxglove", "--layout-out", str(layout))
    assert told.returncode == 0 and str(layout) in told.stdout and "format 1" in told.stdout
    # the layout made for that log's own tree: one row per leaf, labelled with the leaf's path
    rows = json.loads(layout.read_text())["configById"]["StateTransitions!leaves"]["paths"]
    nodes = open_log(OLD).nodes
    leaves = [info.path for uid, info in sorted(nodes.items()) if all(n.parent != uid for n in nodes.values())]
    assert leaves and [row["label"] for row in rows] == leaves
