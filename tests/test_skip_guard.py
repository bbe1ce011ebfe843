"""The CI guard: under CI=true a skipped real-client test fails the run; elsewhere it skips with its reason."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent

SAMPLE = '''
import pytest

@pytest.mark.real_client
def test_needs_a_browser():
    pytest.skip("no chromium on this machine")

def test_ordinary_skip():
    pytest.skip("not relevant here")
'''


def _session(tmp_path: Path, ci: str | None) -> subprocess.CompletedProcess[str]:
    (tmp_path / "test_sample.py").write_text(SAMPLE)
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    if ci is not None:
        env["CI"] = ci
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-ra", "-p", "skip_guard", "-p", "no:cacheprovider",
         "--rootdir", str(tmp_path), "-c", os.devnull, str(tmp_path / "test_sample.py")],
        capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env,
    )


def test_under_ci_a_real_client_skip_is_a_failure(tmp_path: Path) -> None:
    proc = _session(tmp_path, "true")
    assert proc.returncode == 1, proc.stdout
    assert "1 failed, 1 skipped" in proc.stdout
    assert "a real-client test may not skip (no chromium on this machine)" in proc.stdout


def test_outside_ci_the_skip_stays_with_its_reason_printed(tmp_path: Path) -> None:
    proc = _session(tmp_path, None)
    assert proc.returncode == 0, proc.stdout
    assert "2 skipped" in proc.stdout
    assert "no chromium on this machine" in proc.stdout
