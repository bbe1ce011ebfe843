"""`bt-grasp run --json` (issue 24): the summary as exactly one JSON object on stdout, typed (numbers as numbers),
the same as --summary-json writes; progress stays on stderr. (No such option on main as it was: a usage error.)"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
CALIB = REPO / "tests/data/calibration/tabletop_eye_to_hand.yaml"


@pytest.mark.sim
def test_run_json_prints_one_typed_object(tmp_path: Path) -> None:
    written = tmp_path / "summary.json"
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml",
         "--seed", "3", "--calibration", str(CALIB), "--json", "--summary-json", str(written)],
        cwd=REPO, capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)  # the whole of stdout is one JSON object
    assert summary == json.loads(written.read_text())
    assert summary["success"] is True and summary["seed"] == 3 and isinstance(summary["ticks"], int)
    assert "tick " not in proc.stderr  # live progress is drawn on a terminal only, never into a pipe


def test_run_json_and_interactive_do_not_go_together(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--json", "--interactive"])
    assert code == 2 and capsys.readouterr().err == (
        "bt-grasp: error: --json: an interactive run draws on the terminal; drop --json or --interactive\n"
    )
