"""`bt-grasp replay` text shows blackboard values as BT.CPP prints them; the log keeps them typed."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

from bt_grasp.recording import render
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder
from bt_grasp.tree import builtin_registry, load_tree_from_string


def test_blackboard_values_print_like_btcpp() -> None:
    console = Console(width=100, record=True)
    console.print(render.mapping_table("blackboard", {"half": 2.0, "n": 4, "ok": True, "name": "red", "xs": [1, 2]}))
    text = console.export_text()
    assert "2.000000" in text and " 4" in text and "true" in text and "red" in text and "[1,2]" in text


def test_the_log_keeps_script_values_typed(tmp_path: Path) -> None:
    # a script's real 2.0 and integer 4 stay JSON numbers in /bt/tick (Foxglove can plot them); only the
    # text views render them as BT.CPP does
    tree = load_tree_from_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><Script code="half := 6 / 3; n := 4"/></BehaviorTree></root>',
        builtin_registry(),
    )
    tree.tick()
    path = tmp_path / "run.mcap"
    node = {"uid": 1, "path": "S", "type": "Script", "name": "S", "kind": "Action", "status": "SUCCESS", "ticked": True}
    with RunRecorder(path, metadata={"seed": "0"}, handle_signals=False) as rec:
        rec.write_tick(1, 10_000_000, [node], tree.blackboard_values())
    raw = next(open_log(path).iter_messages("/bt/tick")).message
    assert raw["bb"] == {"half": 2.0, "n": 4} and isinstance(raw["bb"]["half"], float)
    assert isinstance(raw["bb"]["n"], int)
