"""The Foxglove layout is made for the tree that runs (issue 24), never shipped for one tree: one State
Transitions row per leaf of that tree, labelled by the leaf's path and read from ``/bt/tick.leaves.<key>``.
Before, the shipped layout listed pick.xml's seven leaves by bare name whatever tree ran."""

from __future__ import annotations

import json
from pathlib import Path

from bt_grasp.behaviours.library import robot_registry
from bt_grasp.foxglove.layout import layout_path
from bt_grasp.foxglove.tree_layout import STATE_PANEL, layout_for_tree_file, write_live_layout
from bt_grasp.recording import topics
from bt_grasp.tree.loader import load_tree

ROOT = Path(__file__).resolve().parents[2]


def _leaf_paths(tree: Path) -> list[str]:
    loaded = load_tree(tree, robot_registry())
    return [n.bt_path for n in sorted(loaded.nodes(), key=lambda n: n.bt_uid) if not n.children]


def test_a_tree_gets_its_own_leaves_as_rows_and_the_shipped_base_names_none() -> None:
    for name in ("pick.xml", "sort_by_color.xml", "stack.xml"):
        tree = ROOT / "trees" / name
        panel = layout_for_tree_file(tree)["configById"][STATE_PANEL]
        leaves = _leaf_paths(tree)
        assert [row["label"] for row in panel["paths"]] == leaves, name
        assert [row["value"] for row in panel["paths"]] == [f"/bt/tick.leaves.{k}" for k in topics.leaf_keys(leaves)]
        assert panel["foxglovePanelTitle"] == f"State Transitions: {name}"
    assert json.loads(layout_path().read_text())["configById"][STATE_PANEL]["paths"] == []


def test_a_live_run_writes_its_layout_beside_its_log_or_in_a_private_folder(tmp_path: Path) -> None:
    tree = ROOT / "trees" / "sort_by_color.xml"
    beside = write_live_layout(tree, log=tmp_path / "runs" / "a.mcap")
    assert beside == tmp_path / "runs" / "a.layout.json"
    assert json.loads(beside.read_text()) == layout_for_tree_file(tree)
    control = json.loads(write_live_layout(tree, log=tmp_path / "b.mcap", control=True).read_text())
    assert "Parameters!control" in control["configById"]  # --control's panels, around this tree's rows
    assert control["configById"][STATE_PANEL] == layout_for_tree_file(tree)["configById"][STATE_PANEL]
    import tempfile

    from bt_grasp.foxglove.tree_layout import live_layout_folder

    assert live_layout_folder(True, tmp_path / "a.mcap") is None and live_layout_folder(False, None) is None
    folder = live_layout_folder(True, None)  # no log: a folder of its own under the temporary directory
    assert folder is not None
    loose = write_live_layout(tree, folder=Path(folder.name))
    assert loose.parent.parent == Path(tempfile.gettempdir()) and loose.name == "sort_by_color.layout.json"
    assert (loose.parent.stat().st_mode & 0o077) == 0  # private to this user
    folder.cleanup()  # what the run command does when the run ends (it was left behind before)
    assert not loose.parent.exists()


def test_a_live_run_without_a_log_leaves_no_folder_behind(tmp_path: Path) -> None:
    """Found by the pre-review attack: each `run --live` without --log left a bt_grasp_layout_* folder in the
    temporary directory."""
    import os
    import subprocess
    import sys

    tmp = tmp_path / "tmp"
    tmp.mkdir()
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "run", str(ROOT / "trees/pick.xml"), "--scene",
                           str(ROOT / "scenes/tabletop.yaml"), "--max-ticks", "3", "--quiet", "--live", "0"],
                          capture_output=True, text=True, timeout=300, env={**os.environ, "TMPDIR": str(tmp)})
    assert proc.returncode in (0, 1), proc.stderr[-2000:]
    assert "layout: " + str(tmp) in proc.stderr, proc.stderr[-2000:]  # it was there while the run served
    assert [p.name for p in tmp.iterdir() if p.name.startswith("bt_grasp_layout_")] == []
