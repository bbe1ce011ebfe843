"""Campaigns end to end on the simulator: the same per-episode results with 1 worker, with a campaign
interrupted twice (its coordinator killed, then one of 2 workers) and resumed, and on a 2-node local Ray
cluster."""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.campaign.results import read_rows
from bt_grasp.campaign.worker import PLACE_COLUMNS

REPO = Path(__file__).resolve().parents[2]
TINY = REPO / "tests/data/campaigns/tiny.yaml"
BT = [sys.executable, "-m", "bt_grasp.cli.main"]

pytestmark = [pytest.mark.sim, pytest.mark.slow]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _eval(*args: str, timeout: float = 600, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*BT, "eval", "run", *args], capture_output=True, text=True, timeout=timeout, cwd=REPO, env=env or _env()
    )


def _rows(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def _identity(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Each episode's row without the columns that depend on where and when it ran."""
    out = {}
    for row in rows:
        assert row["episode"] not in out, f"episode {row['episode']} has two rows"
        out[row["episode"]] = {k: v for k, v in row.items() if k not in PLACE_COLUMNS}
    return out


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, Any]]:
    out = tmp_path_factory.mktemp("one")
    proc = _eval(str(TINY), "--out", str(out), "--workers", "1", "--keep-logs", "failures")
    assert proc.returncode == 0, proc.stderr
    # the workers leave before nanobind's leak report ("nanobind: leaked 174 types!" and ~30 lines more)
    assert "leaked" not in proc.stderr, proc.stderr[-3000:]
    rows = _rows(out / "tiny.jsonl")
    assert len(rows) == 4
    # failed episodes keep their log, one `bt-grasp replay` away
    for row in rows:
        assert (row["mcap"] is not None) == (not row["success"])
        if row["mcap"]:
            replay = subprocess.run(
                [*BT, "replay", row["mcap"], "--failures"],
                capture_output=True,
                text=True,
                timeout=300,
                cwd=REPO,
                env=_env(),
            )
            assert replay.returncode == 0 and str(row["failure_reason"]) in replay.stdout, replay.stderr
    assert (out / "tiny.parquet").exists()
    return _identity(rows)


def _differences(got: dict[str, dict[str, Any]], want: dict[str, dict[str, Any]]) -> list[str]:
    """Per episode, the columns that differ (empty when the runs are identical)."""
    out = [f"episode {k} only in one run" for k in sorted(set(got) ^ set(want))]
    for key in sorted(set(got) & set(want)):
        cols = sorted(c for c in set(got[key]) | set(want[key]) if got[key].get(c) != want[key].get(c))
        if cols:
            out.append(
                f"{got[key]['tree']} seed {got[key]['seed']} {got[key]['fault_plan']}: "
                + ", ".join(f"{c}: {got[key].get(c)!r} != {want[key].get(c)!r}" for c in cols)
            )
    return out


def _worker_pids(parent: int) -> list[int]:
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid == parent and b"spawn_main" in cmdline:
            pids.append(int(entry.name))
    return pids


def _wait_for_rows(proc: subprocess.Popen[str], results: Path, more_than: int, *, timeout_s: float = 600) -> int:
    """Poll (a condition, not a guess at the speed) until the results file holds more than ``more_than`` rows
    while the coordinator still runs; the row count seen."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert proc.poll() is None, f"the campaign ended (exit {proc.returncode}) before its kill"
        seen = len(read_rows(results)) if results.exists() else 0
        if seen > more_than:
            return seen
        time.sleep(0.05)
    raise AssertionError(f"no row beyond {more_than} within {timeout_s:g} s")


def _popen_eval(out: Path, workers: int) -> subprocess.Popen[str]:
    """A campaign in its own process group (the coordinator, its workers and their log writers)."""
    return subprocess.Popen(
        [*BT, "eval", "run", str(TINY), "--out", str(out), "--workers", str(workers), "--keep-logs", "none"],
        cwd=REPO, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )


def test_killed_coordinator_then_lost_worker_then_resumed_match_one_worker(
    one_worker: dict[str, dict[str, Any]], tmp_path: Path
) -> None:
    """Two interruptions of one 4-episode campaign, each proven to land mid-campaign: fewer rows than episodes
    once the interrupted run ended. 1) the coordinator and everything it started are SIGKILLed (exit by the
    signal) once one row is on disk; 2) the resumed campaign, on 2 workers, loses a worker (SIGKILL) once a new
    row is on disk, while an episode is still open: the pool breaks, every open episode fails and the coordinator
    must say so with exit 3 (exit 0 would claim a finished campaign); 3) a last resume finishes it. Rows written
    before each interruption stay as they were, every episode has exactly one row, and the rows match the
    uninterrupted 1-worker run's."""
    results = tmp_path / "tiny.jsonl"
    total = len(one_worker)
    # 1) the coordinator killed
    proc = _popen_eval(tmp_path, workers=1)
    try:
        _wait_for_rows(proc, results, 0)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == -signal.SIGKILL
    first = results.read_text()
    n_first = len(read_rows(results))
    assert 1 <= n_first < total, f"{n_first} rows after the coordinator's kill: it did not land mid-campaign"
    # 2) resumed, and a worker lost
    proc = _popen_eval(tmp_path, workers=2)
    try:
        _wait_for_rows(proc, results, n_first)
        workers = _worker_pids(proc.pid)
        assert len(workers) == 2, workers
        os.kill(workers[0], signal.SIGKILL)
        _out, err = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    second = results.read_text()
    n_second = len(read_rows(results))
    assert n_first < n_second < total, f"{n_second} rows after the lost worker: it did not land mid-campaign"
    assert proc.returncode == 3, f"exit {proc.returncode} after a lost worker: {err}"
    assert "run the same command again to resume" in err and "Traceback" not in err
    assert second.startswith(first), "a row written before the coordinator's kill changed"
    # 3) resumed to the end
    resumed = _eval(str(TINY), "--out", str(tmp_path), "--workers", "2", "--keep-logs", "none")
    assert resumed.returncode == 0, resumed.stderr
    assert results.read_text().startswith(second), "a row written before the lost worker changed"
    rows = _rows(results)
    assert sorted(r["episode"] for r in rows) == sorted(one_worker)  # every episode exactly once
    assert _differences(_identity(rows), one_worker) == []


#: Ray 2.60 turns token authentication on by itself when ~/.ray/auth_token exists: the test's cluster, its
#: nodes and the campaign's driver all get one explicit token instead (hermetic, and how a real cluster runs)
RAY_TOKEN = {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}


def _ray_env() -> dict[str, str]:
    return {**_env(), **RAY_TOKEN}


def _start(args: list[str], err: Path) -> subprocess.Popen[bytes]:
    with err.open("wb") as f:
        return subprocess.Popen(args, env=_ray_env(), start_new_session=True, stdout=subprocess.DEVNULL, stderr=f)


def _ray_cluster(tmp_path: Path) -> tuple[str, list[subprocess.Popen[bytes]]]:
    """A head and a second node on 127.0.0.1, each `ray start --block` in its own process group."""
    # Ray's socket paths must stay under 107 bytes: a short folder of its own (removed with tmp_path's)
    temp_dir = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp"))
    (tmp_path / "ray-temp-dir").write_text(str(temp_dir))
    ray_bin = Path(sys.executable).with_name("ray")
    if not ray_bin.exists():
        pytest.skip(f"Ray cannot start here: no `ray` command next to {sys.executable}")
    port = 20000 + os.getpid() % 20000
    common = ["--num-cpus=1", "--node-ip-address=127.0.0.1", "--disable-usage-stats", "--block"]
    procs = []
    head = _start(
        [
            str(ray_bin),
            "start",
            "--head",
            f"--port={port}",
            "--include-dashboard=false",
            f"--temp-dir={temp_dir}",
            *common,
        ],
        tmp_path / "head.err",
    )
    procs.append(head)
    address = f"127.0.0.1:{port}"
    time.sleep(2)
    if head.poll() is not None:
        reason = (tmp_path / "head.err").read_text()[-500:]
        pytest.skip(f"Ray cannot start here: the head node exited ({reason.strip()})")
    node = _start([str(ray_bin), "start", f"--address={address}", *common], tmp_path / "node.err")
    procs.append(node)
    return address, procs


def _stop(procs: list[subprocess.Popen[bytes]]) -> None:
    for proc in reversed(procs):  # only the process groups this test started
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            continue
    for proc in reversed(procs):
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)


def _wait_for_nodes(address: str, n: int) -> None:
    """Both nodes up (on a busy machine the head can take tens of seconds to accept connections)."""
    script = (
        "import ray, time\n"
        "t = time.monotonic()\n"
        "while True:\n"
        "    try:\n"
        f"        ray.init(address='{address}', log_to_driver=False)\n"
        "        break\n"
        "    except ConnectionError:\n"
        "        if time.monotonic() - t > 240: raise\n"
        "        time.sleep(1)\n"
        f"while len([x for x in ray.nodes() if x['Alive']]) < {n} and time.monotonic() - t < 240: time.sleep(0.5)\n"
        "print(len([x for x in ray.nodes() if x['Alive']]))\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=_ray_env())
    if out.returncode != 0 or out.stdout.strip() != str(n):
        pytest.skip(f"Ray cannot start here: {n} nodes not up within 240 s ({out.stderr.strip()[-300:]})")


@pytest.mark.real_client
def test_two_node_ray_cluster_matches_local_run(one_worker: dict[str, dict[str, Any]], tmp_path: Path) -> None:
    address, procs = _ray_cluster(tmp_path)
    try:
        _wait_for_nodes(address, 2)
        proc = _eval(
            str(TINY), "--out", str(tmp_path / "out"), "--ray", address, "--keep-logs", "failures", env=_ray_env()
        )
        assert proc.returncode == 0, proc.stderr
    finally:
        _stop(procs)
        shutil.rmtree((tmp_path / "ray-temp-dir").read_text(), ignore_errors=True)
    rows = _rows(tmp_path / "out" / "tiny.jsonl")
    assert len(rows) == 4
    assert len({r["worker"].rsplit(":", 1)[1] for r in rows}) == 2, "both nodes' actors ran episodes"
    assert _differences(_identity(rows), one_worker) == []
