"""The local engine with real worker processes and a stand-in backend (no simulator): a worker killed
mid-campaign loses no finished row and duplicates none; resuming finishes the rest."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

SCRIPT = """
import sys
from pathlib import Path
sys.path.insert(0, {tests!r})
from campaign.standin import stand_in
from bt_grasp.campaign.local import LocalEngine
from bt_grasp.campaign.runner import CampaignIncomplete, run_campaign
from bt_grasp.campaign.spec import load_campaign
from bt_grasp.campaign.worker import KeepLogs
campaign = load_campaign({campaign!r}, check_inputs=False)
out = Path({out!r})
try:
    run_campaign(campaign, out, lambda: LocalEngine(2, stand_in, out / "logs", KeepLogs.NONE))
except CampaignIncomplete as exc:
    print("INCOMPLETE", exc)
    sys.exit(3)
"""


def _children(parent: int) -> list[int]:
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
                cmdline = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == parent and b"spawn_main" in cmdline:
                pids.append(int(entry.name))
    return pids


def test_killed_worker_loses_and_duplicates_no_row(tmp_path: Path) -> None:
    campaign = tmp_path / "c.yaml"
    campaign.write_text(
        f"name: c\ntrees: [{REPO / 'trees/pick.xml'}]\nscenes: [{REPO / 'scenes/tabletop.yaml'}]\n"
        "seeds: {first: 0, count: 24}\n"
    )
    out = tmp_path / "out"
    script = SCRIPT.format(tests=str(REPO / "tests"), campaign=str(campaign), out=str(out))
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, text=True)
    results = out / "c.jsonl"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not (results.exists() and results.read_text().count("\n") >= 3):
            time.sleep(0.05)
        workers = _children(proc.pid)
        assert len(workers) == 2, workers
        os.kill(workers[0], signal.SIGKILL)
        stdout, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 3, stdout
    before = results.read_text()
    rows_before = [json.loads(x) for x in before.splitlines()]
    assert 3 <= len(rows_before) < 24
    again = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stdout + again.stderr
    after = results.read_text()
    assert after.startswith(before), "a row written before the kill changed"
    rows = [json.loads(x) for x in after.splitlines()]
    assert sorted(r["seed"] for r in rows) == list(range(24)), "each episode exactly once"
    assert all(r["success"] == (r["seed"] % 3 != 0) for r in rows)


def test_workers_run_with_one_openblas_thread(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A worker process gets the campaign's worker environment before it imports numpy (OpenBLAS's spinning
    second thread took a core from the other worker)."""
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.syspath_prepend(str(REPO / "tests"))
    from bt_grasp.campaign.local import LocalEngine
    from bt_grasp.campaign.spec import load_campaign
    from bt_grasp.campaign.worker import KeepLogs
    from campaign.standin import env_probe

    campaign_file = tmp_path / "c.yaml"
    campaign_file.write_text(f"name: c\ntrees: [{REPO / 'trees/pick.xml'}]\n"
                             f"scenes: [{REPO / 'scenes/tabletop.yaml'}]\nseeds: {{first: 1, count: 1}}\n")
    episodes = load_campaign(campaign_file, check_inputs=False).episodes()
    rows = list(LocalEngine(1, env_probe, tmp_path / "logs", KeepLogs.NONE).run(episodes))
    assert [row["fingerprint"] for row in rows] == ["OPENBLAS_NUM_THREADS=1"]  # type: ignore[index]
