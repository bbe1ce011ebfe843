"""open3d's drawing helpers (plotly, dash) stay unloaded in the perception pipeline, and still work when used
(issue 27: ~42 MiB and 0.3-0.7 s of every run that perceives). Each check runs in a fresh interpreter."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

_PROBE = """
import json, sys
{setup}
import bt_grasp.perception.cloud, bt_grasp.perception.segment
print(json.dumps(sorted({{m.split(".")[0] for m in sys.modules}})))
"""


def _top_level_modules(repo_root: Path, setup: str = "") -> set[str]:
    done = subprocess.run([sys.executable, "-c", _PROBE.format(setup=setup)], cwd=repo_root,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


def test_the_pipeline_loads_open3d_without_its_drawing_helpers(repo_root: Path) -> None:
    modules = _top_level_modules(repo_root)
    assert "open3d" in modules  # the probe did import the modules that use open3d
    assert sorted({"dash", "plotly", "flask", "werkzeug"} & modules) == []


def test_without_the_deferral_open3d_loads_dash(repo_root: Path) -> None:
    """The check above can fail: with the finder taken out before the pipeline imports open3d, dash loads."""
    setup = "import bt_grasp.process.slim_imports as s; s.defer_unused_submodules = lambda: None"
    assert "dash" in _top_level_modules(repo_root, setup)


def test_a_deferred_module_still_works_when_used(repo_root: Path) -> None:
    code = """
import sys
import bt_grasp.perception.cloud
import open3d
assert "dash" not in sys.modules
draw = open3d.visualization.draw_plotly  # the first attribute read runs the module
assert callable(draw) and "dash" in sys.modules
from open3d.visualization import get_plotly_fig
assert callable(get_plotly_fig)
print("ok")
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=repo_root, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("ok")
