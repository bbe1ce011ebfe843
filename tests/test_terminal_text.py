"""Terminal control characters from files and peers are shown, never obeyed (found by the pre-review attack: Rich
escapes markup but passes ESC through, click keeps it on a terminal, and the Foxglove SDK's log lines quote what a
viewer sent). ``bt_grasp.files.terminal_text`` is applied where such text reaches the terminal: log contents when read,
error sentences, the live server's lines."""

from __future__ import annotations

import logging
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.files.terminal_text import may_hold_controls, shown, shown_deep

REPO = Path(__file__).resolve().parents[1]
ESC = "\x1b[2J\x1b]0;owned\x1b\\\x07\u202e\x9b"


def test_every_control_character_is_written_visibly() -> None:
    assert shown(ESC) == "\\x1b[2J\\x1b]0;owned\\x1b\\\\x07\\u202e\\x9b"
    assert shown("tab\tand\nnewline") == "tab\tand\nnewline"
    assert shown("one\nline", newlines=False) == "one\\x0aline"
    assert shown("plain ümlaut 漢字 [/] $x$") == "plain ümlaut 漢字 [/] $x$"
    assert shown_deep({"k\x1b": ["a\x1b", 1, None]}) == {"k\\x1b": ["a\\x1b", 1, None]}


def test_the_json_fast_test_finds_what_json_escapes() -> None:
    import json

    assert may_hold_controls(json.dumps(ESC))
    assert may_hold_controls(json.dumps("\u202e"))
    assert not may_hold_controls(json.dumps({"name": "Grasp", "reason": "slipped", "x": "\u00e9\u4e2d"}))


def test_an_error_sentence_quoting_a_file_shows_its_control_characters(tmp_path: Path) -> None:
    tree = tmp_path / "t.yaml"
    tree.write_text('btcpp_format: 4\ntrees:\n  Main:\n    "Evil\\e[2J\\e]0;owned\\e\\\\"\n')
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "tree", "validate", str(tree)],
                          capture_output=True, text=True, timeout=120, env={"TERM": "xterm", "PATH": ""})
    assert proc.returncode == 2, proc.stderr
    assert "Evil\\x1b[2J" in proc.stderr and "\x1b" not in proc.stderr, proc.stderr


def test_the_live_servers_lines_are_one_safe_line_each(capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.live_log import LiveServerLog, show_live_server_log

    show_live_server_log()
    show_live_server_log()
    logger = logging.getLogger("foxglove.websocket.connected_client")
    logger.error("Invalid message from 127.0.0.1:1: unknown variant `%s`", ESC + "\n" + "x" * 1000)
    logger.info("Registered client 127.0.0.1:1")  # info stays quiet, as before
    err = capsys.readouterr().err
    assert err.startswith("live server: Invalid message") and err.count("\n") == 1 and "\x1b" not in err
    assert err.rstrip().endswith("...") and len(err) < 330
    assert sum(isinstance(h, LiveServerLog) for h in logging.getLogger("foxglove").handlers) == 1
