"""Ctrl-C mid-run (issue 24): it exited 130 with no word, and replay of its log said "no result recorded".
Now the log is finished with a result that says the run was interrupted (not judged), one line is printed,
and the exit code is 130."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.cli.main import main
from tests.terminal_stderr import TerminalStderr

REPO = Path(__file__).resolve().parents[2]
LINE = "bt-grasp: error: interrupted (Ctrl-C)"


def _ctrl_c_reaches_the_child() -> None:
    """Run in the child before exec: a terminal's Ctrl-C reaches a foreground command, but a suite started in the
    background by a non-interactive shell (nohup, CI runners) hands its children SIGINT ignored, and Python keeps
    it ignored, so the signal below would do nothing and the run would end normally (exit 0)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.sim
def test_ctrl_c_mid_run_finishes_the_log_marked_interrupted(tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    # stderr on a terminal, where the run draws its progress (never into a pipe): tick 100 is waited for there
    run = TerminalStderr(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml",
         "--log", str(log), "--realtime", "0.3"],  # slowed down: tick 100 comes long before the end
        cwd=REPO, stdout=subprocess.PIPE, text=True, preexec_fn=_ctrl_c_reaches_the_child,
    )
    proc = run.proc
    seen = []
    lines = run.lines()
    for line in lines:
        seen.append(line)
        if line.startswith("tick   100"):
            proc.send_signal(signal.SIGINT)
            break
    rest = [line for line in lines if not line.startswith("tick ")]  # until the command ends: its last words
    out, _ = proc.communicate(timeout=120)
    run.close()
    assert proc.returncode == 130, "\n".join(seen + rest)
    assert [line.strip() for line in rest] == [LINE] and out == ""
    replay = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--json"],
                            cwd=REPO, capture_output=True, text=True, timeout=120)
    assert replay.returncode == 0, replay.stderr
    summary = json.loads(replay.stdout)
    result = summary["result"]
    assert summary["interrupted"] is True and summary["success"] is None and summary["seed"] == 0
    assert result["reason"] == "INTERRUPTED" and result["tree_status"] == "RUNNING"
    assert 100 <= result["ticks"] <= 110 and not summary["truncated"]
    text = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log)],
                          cwd=REPO, capture_output=True, text=True, timeout=120).stdout
    assert f"INTERRUPTED (Ctrl-C) at tick {result['ticks']}: not judged" in text and "no result" not in text


def test_a_command_ended_by_ctrl_c_says_so_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import bt_grasp.tree.loader as loader

    def interrupted(*_: object, **__: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(loader, "load_tree", interrupted)
    code = main(["tree", "validate", str(REPO / "trees/pick.xml")])
    captured = capsys.readouterr()
    assert (code, captured.out, captured.err) == (130, "", LINE + "\n")  # typer's own answer was silence
