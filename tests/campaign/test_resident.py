"""`bt-grasp run --resident`: the second run is served warm by the same process, gives the same result as
the first, and bad input still exits 2 with one line."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]


@pytest.mark.sim
@pytest.mark.slow
def test_second_resident_run_is_served_warm_with_the_same_result(tmp_path: Path) -> None:
    env = dict(os.environ, BT_GRASP_RESIDENT_DIR=str(tmp_path / "resident"))
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [*BT, "run", *args, "--resident"], capture_output=True, text=True, timeout=600, cwd=REPO, env=env
        )

    try:
        pids, summaries = [], []
        for i in range(2):
            out = tmp_path / f"summary{i}.json"
            proc = run(
                "trees/pick.xml",
                "--scene",
                "scenes/tabletop.yaml",
                "--seed",
                "3",
                "--summary-json",
                str(out),
            )
            assert proc.returncode == 0, proc.stderr  # the pick must succeed, judged by physics
            pids.append(proc.stderr.split("(ran in the resident process ")[1].split(")")[0])
            summary = json.loads(out.read_text())
            summary.pop("wall_time_s")
            summary.get("planning", {}).pop("wall_s", None)  # wall-clock figures differ from run to run
            summaries.append(summary)
        assert pids[0] == pids[1], "the second run was not served by the resident process"
        assert summaries[0] == summaries[1]
        bad = run("trees/nope.xml", "--scene", "scenes/tabletop.yaml")
        assert bad.returncode == 2
        lines = bad.stderr.strip().splitlines()
        assert len(lines) == 1 and "nope.xml: no such file" in lines[0], bad.stderr
    finally:
        stop = "from bt_grasp.resident.client import stop_resident; stop_resident()"
        subprocess.run([sys.executable, "-c", stop], env=env, timeout=60, check=False)
