"""One node, one name (issue 24): a run of ``trees/sort_by_color.xml`` walked through every output finds the
same names, each node's path (BT.CPP's fullPath: subtree instance / name, ``name::uid`` for a node without a
name of its own), with its uid alongside where there is room.

One episode runs through the campaign path (``eval run``, the log kept), with a dropped frame so a leaf fails
and is retried, and a tick limit so the episode ends failed after about 4 s of simulated time. Then:
``tree show`` (text and dot), ``replay`` (text timeline, JSON summary, failures view in text and JSON, one
tick's tree), the run report's Gantt rows and failures table, the campaign's results row, the ``/bt/tick``
leaves and the Foxglove layout attached to the log. Before, these said ``OpenGripper``, ``OpenGripper_2``,
``OpenGripper@588`` or ``OpenGripper (PickObject::18/OpenGripper::26)`` depending on the tool.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.foxglove.tree_layout import LAYOUT_ATTACHMENT, STATE_PANEL
from bt_grasp.recording import report, report_figures, topics
from bt_grasp.recording.reader import open_log

ROOT = Path(__file__).resolve().parents[2]
TREE = ROOT / "trees" / "sort_by_color.xml"

pytestmark = pytest.mark.sim

CAMPAIGN = f"""
name: walk
trees: [{TREE}]
scenes: [{ROOT / "scenes" / "sort_by_color.yaml"}]
seeds: [0]
fault_plans:
  - {{name: drop, inject: ["frame_drop@Perceive#1"]}}
max_ticks: 400
"""


def _cli(*args: str, cwd: Path) -> str:
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], capture_output=True, text=True,
                          timeout=600, cwd=cwd, env={**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "400"})
    assert proc.returncode == 0, (args, proc.stdout[-3000:], proc.stderr[-3000:])
    return proc.stdout


@pytest.fixture(scope="module")
def walked(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("walk")
    (folder / "walk.yaml").write_text(CAMPAIGN)
    _cli("eval", "run", "walk.yaml", "--out", "out", "--workers", "1", "--keep-logs", "all", "--no-parquet",
         cwd=folder)
    rows = [json.loads(line) for line in (folder / "out" / "walk.jsonl").read_text().splitlines()]
    assert len(rows) == 1
    return {"folder": folder, "row": rows[0], "log": Path(rows[0]["mcap"])}


def _tree_show_paths(folder: Path) -> dict[int, str]:
    text = _cli("tree", "show", str(TREE), cwd=folder)
    found = dict(re.findall(r"#(\d+) (\S+)\s*$", text, flags=re.M))
    return {int(uid): path for uid, path in found.items()}


def test_every_output_names_a_node_by_the_same_path(walked: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    folder, row, log = walked["folder"], walked["row"], walked["log"]
    run = open_log(log)
    # the tree as recorded in the log; tree show (text and dot) draws the same uids and paths
    paths = {uid: info.path for uid, info in run.nodes.items()}
    leaves = [info.path for _, info in sorted(run.nodes.items()) if info.is_leaf]
    assert len(paths) > 60 and len(set(paths.values())) == len(paths)
    assert _tree_show_paths(folder) == paths
    dot = _cli("tree", "show", str(TREE), "--format", "dot", cwd=folder)
    assert {int(u): p for u, p in re.findall(r'n(\d+) \[label=".*\\n([^\s\\]+) #\1"', dot)} == paths
    assert "PickObject::18/OpenGripper::26" in paths.values()
    names = set(paths.values())

    # replay: the JSON summary, the failures (text and JSON), one tick's tree, the timeline's changes
    summary = json.loads(_cli("replay", str(log), "--json", cwd=folder))
    assert summary["failed_path"] in names and summary["failed_path"] == row["failed_path"]
    assert set(summary["retries_per_leaf"]) | set(summary["failures_per_leaf"]) <= names
    assert "PickObject::18/Perceive::28" in summary["retries_per_leaf"]  # the dropped frame, retried
    failures = json.loads(_cli("replay", str(log), "--failures", "--json", cwd=folder))
    assert failures and {f["path"] for f in failures} <= names
    assert {c["path"] for f in failures for c in f["recovery"]} <= names
    assert {p for f in failures for p in f["propagated_to"]} <= names
    text = _cli("replay", str(log), "--failures", cwd=folder)
    assert "PickObject::18/Perceive::28  NO_FRAME" in text
    shown = set(re.findall(r"(\S+) \(tick \d+\) (?:RUN|OK|FAIL|idle|skip)", text))
    assert shown and shown <= names
    tick = json.loads(_cli("replay", str(log), "--tick", "30", "--json", cwd=folder))["tree"]

    def walk(node: dict[str, Any]) -> dict[int, str]:
        return {node["uid"]: node["path"]} | {k: v for c in node["children"] for k, v in walk(c).items()}

    assert walk(tick) == paths
    timeline = _cli("replay", str(log), "--max-rows", "100000", cwd=folder)
    changed = set(re.findall(r"(\S+) (?:RUN|OK|FAIL|idle|skip)(?=\s)", timeline))
    assert "PickObject::18/OpenGripper::26" in changed and changed <= names, changed - names

    # the run report: the Gantt's rows, the failures table
    gantt: list[Any] = []
    real = report_figures.gantt
    monkeypatch.setattr(report_figures, "gantt", lambda *a, **k: gantt.append(a) or real(*a, **k))
    page = report.build_report(run, folder / "report.html").html_path.read_text()
    rows_drawn = gantt[0][0]
    assert rows_drawn and set(rows_drawn) <= set(leaves)
    assert "PickObject::18/Perceive::28" in rows_drawn
    table = page[page.index("<h2>Failures and recovery"):page.index("<h3>Injected faults")]
    cells = set(re.findall(r"<td>tick \d+</td><td>([^<]+)</td>", table))
    assert "frame_drop@Perceive#1: no frame" in page
    assert cells and cells <= names

    # the campaign's results row
    assert row["failed_path"] in names and row["failed_path"] == run.result["failed_path"]
    assert row["retries"] == {"PickObject::18/Perceive::28": 1} == run.result["retries"]
    assert row["failed_leaf"] == row["failed_path"].rsplit("/", 1)[-1].split("::")[0]

    # Foxglove: the leaves on /bt/tick and the layout attached to the log, one row per leaf, by path
    keys = next(m.message["leaves"] for m in run.iter_messages(topics.TICK) if m.message.get("leaves"))
    assert list(keys) == topics.leaf_keys(leaves)
    layout = json.loads(run.attachments[LAYOUT_ATTACHMENT])
    rows = layout["configById"][STATE_PANEL]["paths"]
    assert [r["label"] for r in rows] == leaves
    assert [r["value"] for r in rows] == [f"/bt/tick.leaves.{k}" for k in keys]
