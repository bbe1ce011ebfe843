"""`bt-grasp --help` and `bt-grasp tree validate` import none of the heavy libraries a run needs (issue 27: they
took 0.95 s, mostly imports no such command uses). Checked in a fresh interpreter's ``sys.modules``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("open3d", "matplotlib", "pyarrow", "ray", "foxglove", "sapien", "cv2", "pinocchio", "ompl", "scipy", "mcap",
         "textual",  # textual: only `run --interactive` draws a terminal UI
         "onnxruntime", "onnx")  # only a learned detector loads a model

_PROBE = """
import json, sys
from bt_grasp.cli.main import main
code = main(sys.argv[1:])
print(json.dumps({"code": code, "modules": sorted(m for m in sys.modules if "." not in m)}))
"""


@pytest.mark.parametrize("argv", [["--help"], ["tree", "validate", "trees/pick.xml"], ["run", "--help"],
                                  ["detector", "--help"]],
                         ids=["help", "validate", "run-help", "detector-help"])
def test_the_command_imports_no_heavy_library(repo_root: Path, argv: list[str]) -> None:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv], cwd=repo_root, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["code"] == 0
    assert "bt_grasp" in report["modules"]  # the probe did run the command
    assert sorted(set(HEAVY) & set(report["modules"])) == []
