"""``bt-grasp bench cell-faults``: each fault a real cell can meet, injected mid-motion into a run against the twin.

A run (``bt-grasp run SHUTTLE --cell CELL --yes``, a process of its own) moves the arm back and forth between two
poses; once the arm moves faster than :data:`MOVING_RAD_S`, the fault is injected:

| fault | how | the run's reason |
| --- | --- | --- |
| ``protective-stop`` | the twin's ``fault protective-stop`` (as a collision would) | ``PROTECTIVE_STOP`` |
| ``twin-killed`` | SIGKILL to the twin's process (the controller and its network gone) | ``CONNECTION_LOST`` |
| ``gripper-silent`` | the twin's ``fault gripper-silent`` (the URCap stops answering) | ``GRIPPER_NOT_ANSWERING`` |
| ``sigstop`` | SIGSTOP to the run's process (resumed 1 s later): the controller's watchdog | ``WATCHDOG`` |
| ``ctrl-c`` | SIGINT to the run's process | ``INTERRUPTED`` |

Measured per trial: how long after the injection the twin reports every joint slower than :data:`STILL_RAD_S`
(``stop_ms``; none when the twin itself was killed), how long until the run recorded the fault in its log
(``seen_ms``: the fault's event in the log, whose times are the run's wall clock; for SIGSTOP the run cannot see
anything until it is resumed, so none), the reason the log's result gives, and whether ``bt-grasp replay --json``
reads the log. A twin serves every trial of a fault (a new one after each ``twin-killed``).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_grasp.bench.twin_process import TwinProcess, start_twin
from bt_grasp.hardware.twin_control import TwinControlError

SHUTTLE_TREE = """<?xml version="1.0"?>
<!-- bench cell-faults: the arm back and forth across the table, until a fault ends the run -->
<root BTCPP_format="4" main_tree_to_execute="Shuttle">
  <BehaviorTree ID="Shuttle">
    <Repeat num_cycles="50">
      <Sequence>
        <MoveTo pose="0.45;0.14;0.24"/>
        <MoveTo pose="0.45;-0.14;0.24"/>
      </Sequence>
    </Repeat>
  </BehaviorTree>
</root>
"""

EXPECTED = {"protective-stop": "PROTECTIVE_STOP", "twin-killed": "CONNECTION_LOST",
            "gripper-silent": "GRIPPER_NOT_ANSWERING", "sigstop": "WATCHDOG", "ctrl-c": "INTERRUPTED"}
FAULTS = tuple(EXPECTED)
#: the fault is injected once some joint moves faster than this (mid-motion)
MOVING_RAD_S = 0.15
#: the arm stands still once every joint is slower than this
STILL_RAD_S = 0.01
SCENE = "scenes/tabletop.yaml"


@dataclass(frozen=True)
class Trial:
    fault: str
    reason: str | None
    stop_ms: float | None
    seen_ms: float | None
    replayed: bool
    exit_code: int | None


def _speed(twin: TwinProcess) -> float:
    status = twin.control("status", timeout_s=2.0)
    return max(abs(float(v)) for v in status["actual_qd"])


def _wait_moving(twin: TwinProcess, run: subprocess.Popen[bytes], timeout_s: float = 90.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if run.poll() is not None:
            raise RuntimeError(f"the run ended (exit {run.returncode}) before the arm moved")
        if _speed(twin) > MOVING_RAD_S:
            return
        time.sleep(0.005)
    raise RuntimeError(f"the arm did not move within {timeout_s:g} s")


def _wait_still(twin: TwinProcess, since: float, timeout_s: float = 5.0) -> float | None:
    while time.monotonic() - since < timeout_s:
        try:
            if _speed(twin) < STILL_RAD_S:
                return (time.monotonic() - since) * 1000.0
        except TwinControlError:
            return None
        time.sleep(0.002)
    return None


def _from_log(log: Path, injected_unix_ns: int) -> tuple[str | None, float | None, bool]:
    """(the result's reason, ms from the injection to the fault's event in the log, replay read it)."""
    replay = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "replay", str(log), "--json"],
                            capture_output=True, text=True, timeout=120, check=False)
    replayed = replay.returncode == 0 and "Traceback" not in replay.stderr
    reason, seen = None, None
    if replayed:
        summary = json.loads(replay.stdout)
        result = summary.get("result") or {}
        reason = result.get("reason")
    with contextlib.suppress(Exception):
        from bt_grasp.recording.reader import open_log

        run = open_log(log)
        marks = [e["stamp_ns"] for e in run.events if e["kind"] == "cell_fault"]
        marks += [m["stamp_ns"] for m in run.logs if m["name"] == "cell" and "interrupted" in m["message"]]
        if marks:
            seen = (run.time_origin_ns + min(marks) - injected_unix_ns) / 1e6
    return reason, seen, replayed


def one_trial(fault: str, twin: TwinProcess, tree: Path, workdir: Path, number: int) -> Trial:
    """Run the shuttle on ``twin``, inject ``fault`` mid-motion, measure (see the module docstring)."""
    log = workdir / f"{fault}-{number}.mcap"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    run = subprocess.Popen([sys.executable, "-m", "bt_grasp.cli.main", "run", str(tree), "--cell",
                            str(twin.cell_path), "--yes", "--quiet", "--log", str(log)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                           start_new_session=True)  # SIGINT reaches the run alone, not this process
    try:
        _wait_moving(twin, run)
        injected_unix_ns = time.time_ns()
        since = time.monotonic()
        INJECT[fault](twin, run)
        stop_ms = None if fault == "twin-killed" else _wait_still(twin, since)
        if fault == "sigstop":
            time.sleep(max(0.0, 1.0 - (time.monotonic() - since)))
            os.kill(run.pid, signal.SIGCONT)
        code = run.wait(timeout=60)
    finally:
        if run.poll() is None:
            run.kill()
            run.wait()
    reason, seen, replayed = _from_log(log, injected_unix_ns)
    if fault == "sigstop":
        seen = None  # the run was stopped: it sees the watchdog's work once resumed
    if fault == "gripper-silent":
        twin.control("fault gripper-answers")
    return Trial(fault, reason, stop_ms, seen, replayed, code)


def _protective_stop(twin: TwinProcess, run: subprocess.Popen[bytes]) -> None:
    twin.control("fault protective-stop")


def _twin_killed(twin: TwinProcess, run: subprocess.Popen[bytes]) -> None:
    twin.process.kill()


def _gripper_silent(twin: TwinProcess, run: subprocess.Popen[bytes]) -> None:
    twin.control("fault gripper-silent")


def _sigstop(twin: TwinProcess, run: subprocess.Popen[bytes]) -> None:
    os.kill(run.pid, signal.SIGSTOP)


def _ctrl_c(twin: TwinProcess, run: subprocess.Popen[bytes]) -> None:
    os.kill(run.pid, signal.SIGINT)


INJECT: dict[str, Callable[[TwinProcess, subprocess.Popen[bytes]], None]] = {
    "protective-stop": _protective_stop, "twin-killed": _twin_killed, "gripper-silent": _gripper_silent,
    "sigstop": _sigstop, "ctrl-c": _ctrl_c,
}


def recover(twin: TwinProcess) -> None:
    """Back to a twin that takes a new run: a protective stop unlocked (the twin runs with --unlock-delay 0.2)."""
    with contextlib.suppress(TwinControlError):
        status = twin.control("status")
        if status.get("safety_mode") == "PROTECTIVE_STOP":
            deadline = time.monotonic() + 5.0
            from bt_grasp.hardware.ur_dashboard import unlock_protective_stop

            while time.monotonic() < deadline and not unlock_protective_stop(twin.host):
                time.sleep(0.1)


def run_fault_bench(trials: int, faults: tuple[str, ...], progress: Callable[[str], None] | None = None
                    ) -> dict[str, Any]:
    from bt_grasp.process.environment import machine_description

    results: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="bt_grasp_bench_faults_") as tmp:
        work = Path(tmp)
        tree = work / "shuttle.xml"
        tree.write_text(SHUTTLE_TREE)
        twin: TwinProcess | None = None
        try:
            for fault in faults:
                rows: list[Trial] = []
                for number in range(trials):
                    if twin is None or twin.process.poll() is not None:
                        twin = start_twin(SCENE, work, "--unlock-delay", "0.2", salt=number)
                    trial = one_trial(fault, twin, tree, work, number)
                    rows.append(trial)
                    if progress is not None:
                        progress(f"{fault} #{number}: {trial.reason}, arm still after "
                                 f"{_text(trial.stop_ms)} ms, seen by the run after {_text(trial.seen_ms)} ms, "
                                 f"replay {'reads' if trial.replayed else 'CANNOT read'} the log")
                    recover(twin)
                results[fault] = {
                    "trials": len(rows), "expected_reason": EXPECTED[fault],
                    "expected": sum(r.reason == EXPECTED[fault] for r in rows),
                    "reasons": [r.reason for r in rows],
                    "stop_ms": [round(r.stop_ms, 1) for r in rows if r.stop_ms is not None],
                    "seen_ms": [round(r.seen_ms, 1) for r in rows if r.seen_ms is not None],
                    "replayed": sum(r.replayed for r in rows),
                }
        finally:
            if twin is not None:
                twin.stop()
    return {"faults": results, "machine": machine_description()}


def _text(value: float | None) -> str:
    return "-" if value is None else f"{value:.0f}"
