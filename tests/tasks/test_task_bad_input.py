"""Task trees that do not fit their scene are bad input: exit 2, file:line, one sentence, nothing run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BAD = REPO / "tests" / "data" / "bad_task_trees"

CASES = {
    "place_off_table.xml": (6, "Place pose (0.350, 0.950) m is off the table"),
    "place_unreachable.xml": (5, "is out of reach"),
    "unknown_fixture.xml": (5, "no fixture named 'left_tray' in the scene"),
    "malformed_pose.xml": (5, "expected a pose 'x;y[;z[;yaw_deg[;frame]]]'"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_tree_not_fitting_the_scene_is_refused_before_anything_is_built(name: str) -> None:
    from bt_grasp.episode import EpisodeRequest, load_inputs
    from bt_grasp.errors import InputError

    line, fragment = CASES[name]
    with pytest.raises(InputError) as info:
        load_inputs(EpisodeRequest(tree=BAD / name, scene=REPO / "scenes" / "tabletop.yaml"))
    message = str(info.value)
    assert message.startswith(f"{BAD / name}:{line}:") and fragment in message and "\n" not in message, message


@pytest.mark.sim
@pytest.mark.parametrize("name", ["place_off_table.xml"])
def test_tree_not_fitting_the_scene_exits_2(name: str, tmp_path: Path) -> None:
    line, fragment = CASES[name]
    log = tmp_path / "run.mcap"
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(BAD / name), "--scene", "scenes/tabletop.yaml",
         "--log", str(log), "--quiet"],
        capture_output=True, text=True, timeout=300, cwd=REPO,
    )
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"bt-grasp: error: {BAD / name}:{line}:"), proc.stderr
    assert fragment in lines[0], lines[0]
    assert not log.exists() and proc.stdout.strip() == ""
