"""`bt-grasp replay` text shows blackboard values as BT.CPP prints them; the log keeps them typed."""

from __future__ import annotations

from rich.console import Console

from bt_grasp.recording import render


def test_blackboard_values_print_like_btcpp() -> None:
    console = Console(width=100, record=True)
    console.print(render.mapping_table("blackboard", {"half": 2.0, "n": 4, "ok": True, "name": "red", "xs": [1, 2]}))
    text = console.export_text()
    assert "2.000000" in text and " 4" in text and "true" in text and "red" in text and "[1,2]" in text
