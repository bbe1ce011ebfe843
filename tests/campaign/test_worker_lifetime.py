"""Campaign workers end with their coordinator, even one killed with SIGKILL (issue 22): each mechanism on its
own (the kernel's parent-death signal, the watchdog, the check for a parent that died first), with real worker
processes and the stand-in backend (no simulator). Also: a killed process's log writer finishes the log and
exits (it does not wait forever)."""

from __future__ import annotations

import importlib.util
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import pytest

from bt_grasp.recording import open_log

REPO = Path(__file__).resolve().parents[2]

#: a coordinator: 2 workers on a campaign long enough to be killed in the middle of it. ``poll_s`` is the
#: workers' watchdog period (an hour: only the kernel's signal can end them in time); ``thread`` runs the campaign
#: from another thread than the main one (then the kernel's signal is not asked for: the watchdog must do it)
COORDINATOR = """
import sys, threading
from pathlib import Path
sys.path.insert(0, {tests!r})
import bt_grasp.campaign.local as local
from campaign.standin import stand_in
from bt_grasp.campaign.runner import run_campaign
from bt_grasp.campaign.spec import load_campaign
from bt_grasp.campaign.worker import KeepLogs
local.PARENT_POLL_S = {poll_s!r}
campaign = load_campaign({campaign!r}, check_inputs=False)
out = Path({out!r})
go = lambda: run_campaign(campaign, out, lambda: local.LocalEngine(2, stand_in, out / "logs", KeepLogs.NONE))
if {thread!r}:
    t = threading.Thread(target=go)
    t.start()
    t.join()
else:
    go()
"""

BOUND_S = 20.0  # how long the workers may take to go once their coordinator is gone


def _stat(pid: int) -> list[str] | None:
    """``/proc/<pid>/stat``'s fields after the command name (state, ppid, ...; start time is field 19), or None."""
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None


def _workers(parent: int) -> dict[int, str]:
    """The coordinator's spawned worker processes: pid -> start time (so a reused pid is not taken for one)."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        fields = _stat(int(entry.name))
        try:
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if fields is not None and int(fields[1]) == parent and b"spawn_main" in cmdline:
            found[int(entry.name)] = fields[19]
    return found


def _alive(pid: int, start: str) -> bool:
    fields = _stat(pid)
    return fields is not None and fields[19] == start and fields[0] not in ("Z", "X")  # a zombie has ended


def _wait_gone(processes: dict[int, str]) -> list[int]:
    """The processes still alive after BOUND_S (polled: no assumption about the machine's speed)."""
    deadline = time.monotonic() + BOUND_S
    while time.monotonic() < deadline:
        alive = [pid for pid, start in processes.items() if _alive(pid, start)]
        if not alive:
            return []
        time.sleep(0.05)
    return [pid for pid, start in processes.items() if _alive(pid, start)]


def _descendants(root: int) -> dict[int, tuple[str, str]]:
    """Every process below ``root``: pid -> (start time, command line)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        fields = _stat(int(entry.name)) if entry.name.isdigit() else None
        if fields is not None:
            children.setdefault(int(fields[1]), []).append(int(entry.name))
    found: dict[int, tuple[str, str]] = {}
    todo = [root]
    while todo:
        for pid in children.get(todo.pop(), []):
            fields = _stat(pid)
            try:
                cmdline = (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ")
            except OSError:
                continue
            if fields is not None:
                found[pid] = (fields[19], cmdline.decode(errors="replace"))
                todo.append(pid)
    return found


def _kill_coordinator_with_workers(tmp_path: Path, poll_s: float, thread: bool) -> tuple[dict[int, str], list[int]]:
    campaign = tmp_path / "c.yaml"
    campaign.write_text(
        f"name: c\ntrees: [{REPO / 'trees/pick.xml'}]\nscenes: [{REPO / 'scenes/tabletop.yaml'}]\n"
        "seeds: {first: 0, count: 200}\n"
    )
    out = tmp_path / "out"
    script = COORDINATOR.format(tests=str(REPO / "tests"), campaign=str(campaign), out=str(out), poll_s=poll_s,
                                thread=thread)
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.DEVNULL)
    workers: dict[int, str] = {}
    try:
        results = out / "c.jsonl"
        deadline = time.monotonic() + 120
        # both workers warm and running episodes: each has written a row
        while time.monotonic() < deadline and not (results.exists() and results.read_text().count("\n") >= 4):
            assert proc.poll() is None, "the coordinator ended before it could be killed"
            time.sleep(0.05)
        workers = _workers(proc.pid)
        assert len(workers) == 2, workers
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        return workers, _wait_gone(workers)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for pid, start in workers.items():  # never leave one behind, whatever the test found
            if _alive(pid, start):
                os.kill(pid, signal.SIGKILL)


def test_workers_die_with_a_killed_coordinator(tmp_path: Path) -> None:
    """The kernel's parent-death signal alone (the watchdog polls once an hour): both workers go."""
    workers, alive = _kill_coordinator_with_workers(tmp_path, poll_s=3600.0, thread=False)
    assert alive == [], f"workers {alive} of {sorted(workers)} outlived their SIGKILLed coordinator by {BOUND_S} s"


def test_workers_spawned_from_another_thread_die_with_a_killed_coordinator(tmp_path: Path) -> None:
    """A campaign run from a thread that is not the main one: the kernel's signal would follow that thread, so
    it is not asked for; the watchdog (polling once a second) ends the workers."""
    workers, alive = _kill_coordinator_with_workers(tmp_path, poll_s=1.0, thread=True)
    assert alive == [], f"workers {alive} of {sorted(workers)} outlived their SIGKILLed coordinator by {BOUND_S} s"


@pytest.mark.parametrize("kernel_signal", [True, False])
def test_a_worker_whose_coordinator_died_before_it_started_exits_at_once(kernel_signal: bool) -> None:
    """The race the kernel's signal cannot cover: the parent died before ``prctl``. Here the process's parent is
    not the coordinator it was told of, as if it had been re-parented already."""
    script = textwrap.dedent(f"""
        import os
        from bt_grasp.campaign.local import tie_to_coordinator
        tie_to_coordinator(os.getppid() + 1, {kernel_signal!r}, 3600.0)
        print("still here", flush=True)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1 and "still here" not in proc.stdout, (proc.returncode, proc.stdout, proc.stderr)


def test_a_worker_with_its_coordinator_alive_keeps_running() -> None:
    """The same call with the true parent: no exit (the check is not a blanket exit)."""
    script = textwrap.dedent("""
        import os
        from bt_grasp.campaign.local import tie_to_coordinator
        tie_to_coordinator(os.getppid(), True, 0.05)
        import time; time.sleep(0.3)
        print("still here", flush=True)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stdout.strip() == "still here", (proc.returncode, proc.stderr)


def test_a_killed_processes_log_writer_finishes_the_log_and_exits(tmp_path: Path) -> None:
    """A worker killed with its coordinator may hold a log writer process: that child finishes the log (the
    ticks handed over before the kill) and then exits, instead of waiting for a parent that is gone."""
    out = tmp_path / "killed.mcap"
    script = textwrap.dedent(f"""
        import time
        from bt_grasp.recording.writer import RunRecorder
        rec = RunRecorder({str(out)!r}, metadata={{"seed": "1"}}, writer_process=True, handle_signals=False)
        for tick in range(1, 21):
            rec.write_tick(tick, tick * 10_000_000, [], {{"tick": tick}}, {{"q_rad": [0.0] * 6}})
            rec.flush_tick()
        time.sleep(0.5)  # the feeder thread has written every batch to the pipe
        print("flushed", flush=True)
        time.sleep(600)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    writers: dict[int, str] = {}
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "flushed"
        for entry in Path("/proc").iterdir():
            fields = _stat(int(entry.name)) if entry.name.isdigit() else None
            if fields is not None and int(fields[1]) == proc.pid:
                with_cmd = (entry / "cmdline").read_bytes()
                if b"bt_grasp.recording.writer_process" in with_cmd:
                    writers[int(entry.name)] = fields[19]
        assert len(writers) == 1, writers
        proc.kill()
        proc.wait(timeout=30)
        assert _wait_gone(writers) == [], "the log writer outlived its SIGKILLed parent"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
        for pid, start in writers.items():
            if _alive(pid, start):
                os.kill(pid, signal.SIGKILL)
    run = open_log(out)
    assert run.indexed and not run.truncated
    assert [t.tick for t in run.ticks] == list(range(1, 21))


RAY_DRIVER = """
import sys, time
from pathlib import Path
sys.path.insert(0, {tests!r})
import ray
from campaign.standin import stand_in
from bt_grasp.campaign.ray_engine import RayEngine
from bt_grasp.campaign.spec import load_campaign
from bt_grasp.campaign.worker import KeepLogs
address = {address!r}
if address != "local":  # a cluster's head can take a while to accept connections on a busy machine
    t = time.monotonic()
    while True:
        try:
            ray.init(address=address, log_to_driver=False)
            ray.shutdown()
            break
        except ConnectionError:
            if time.monotonic() - t > 120:
                raise
            time.sleep(1)
episodes = load_campaign({campaign!r}, check_inputs=False).episodes()
for row in RayEngine(address, 2, stand_in, Path({logs!r}), KeepLogs.NONE).run(episodes):
    print(row["worker"] if isinstance(row, dict) else row, flush=True)
"""


def _ray_head(temp_dir: Path, env: dict[str, str], err: Path) -> tuple[str, subprocess.Popen[bytes]]:
    """A cluster of its own: ``ray start --head --block`` in its own process group."""
    ray_bin = Path(sys.executable).with_name("ray")
    if not ray_bin.exists():
        pytest.skip(f"Ray cannot start here: no `ray` command next to {sys.executable}")
    port = 20000 + (os.getpid() + 7919) % 20000
    with err.open("wb") as f:
        head = subprocess.Popen([str(ray_bin), "start", "--head", f"--port={port}", "--include-dashboard=false",
                                 f"--temp-dir={temp_dir}", "--num-cpus=2", "--node-ip-address=127.0.0.1",
                                 "--disable-usage-stats", "--block"],
                                env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=f)
    return f"127.0.0.1:{port}", head


@pytest.mark.slow
@pytest.mark.real_client
@pytest.mark.parametrize("where", ["local", "cluster"])
def test_ray_actors_die_with_a_killed_driver(tmp_path: Path, where: str) -> None:
    """The driver (coordinator) SIGKILLed mid-campaign. ``local`` (``--ray local``): Ray's raylet and GCS, started
    by the driver, fate-share with it, and so do the episode actors. ``cluster``: the cluster stays, and the
    episode actors, not detached, go with their driver's job (an actor made ``detached`` stays: this catches it).
    (Ray's own dashboard and runtime-env agents of a local cluster took ~63 s to notice: not asserted.)"""
    if importlib.util.find_spec("ray") is None:
        pytest.skip("Ray is not installed (pip install -e '.[ray]')")
    campaign = tmp_path / "c.yaml"
    campaign.write_text(
        f"name: c\ntrees: [{REPO / 'trees/pick.xml'}]\nscenes: [{REPO / 'scenes/tabletop.yaml'}]\n"
        "seeds: {first: 0, count: 500}\n"
    )
    ray_temp = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp"))  # Ray's socket paths must stay short
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + str(REPO / "tests"), RAY_TMPDIR=str(ray_temp),
               RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(32))  # hermetic: no ~/.ray token
    head = None
    address = "local"
    if where == "cluster":
        address, head = _ray_head(ray_temp, env, tmp_path / "head.err")
    script = RAY_DRIVER.format(tests=str(REPO / "tests"), campaign=str(campaign), logs=str(tmp_path / "logs"),
                               address=address)
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE, text=True,
                            start_new_session=True)
    below: dict[int, tuple[str, str]] = {}
    try:
        assert proc.stdout is not None
        actors: set[int] = set()
        while len(actors) < 2:  # both actors warm and running episodes (the rows' worker column: host:pid)
            line = proc.stdout.readline()
            assert line, f"the driver ended (exit {proc.wait()}) before both actors ran an episode"
            actors.add(int(line.strip().rsplit(":", 1)[1]))
        below = {pid: (fields[19], "actor") for pid in actors if (fields := _stat(pid)) is not None}
        if where == "local":
            below.update(_descendants(proc.pid))
        ours = {pid: start for pid, (start, cmd) in below.items()
                if pid in actors or "raylet/raylet" in cmd or "gcs/gcs_server" in cmd}
        assert len(ours) == (2 if where == "cluster" else 4), below
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        alive = _wait_gone(ours)
        assert alive == [], f"outlived their SIGKILLed driver by {BOUND_S} s: {[below[p][1][:60] for p in alive]}"
        if head is not None:
            assert head.poll() is None, "the cluster itself must stay"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
        if head is not None:  # only the process group this test started
            os.killpg(head.pid, signal.SIGTERM)
            try:
                head.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(head.pid, signal.SIGKILL)
                head.wait(timeout=30)
        for pid, (start, _) in below.items():  # Ray's agents too: nothing of the test's cluster stays
            if _alive(pid, start):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(ray_temp, ignore_errors=True)
