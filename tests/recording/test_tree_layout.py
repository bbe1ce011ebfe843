"""The Foxglove layout is made for the tree that runs (issue 24), never shipped for one tree: one State
Transitions row per leaf of that tree, labelled by the leaf's path and read from ``/bt/tick.leaves.<key>``.
Before, the shipped layout listed pick.xml's seven leaves by bare name whatever tree ran."""

from __future__ import annotations

import json
from pathlib import Path

from bt_grasp.behaviours.library import robot_registry
from bt_grasp.recording import topics
from bt_grasp.recording.layout import layout_path
from bt_grasp.recording.tree_layout import STATE_PANEL, layout_for_tree_file, write_live_layout
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

    loose = write_live_layout(tree)  # no log: a new folder of its own under the temporary directory
    try:
        assert loose.parent.parent == Path(tempfile.gettempdir()) and loose.name == "sort_by_color.layout.json"
        assert (loose.parent.stat().st_mode & 0o077) == 0  # private to this user
    finally:
        loose.unlink()
        loose.parent.rmdir()
