"""Same seed, same run on a busy machine: every core busy, two seeded picks, one fingerprint; --resim holds.

A module fixture starts one busy-loop process per core, then runs the same seeded pick twice at once
(so the runs also compete with each other) and keeps both logs; the tests compare the runs' fingerprints
(``bt_grasp.recording.fingerprint``) and re-simulate one log, still under load.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_grasp.recording.fingerprint import fingerprint_of_log
from bt_grasp.recording.reader import open_log

REPO = Path(__file__).resolve().parents[1]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]
PICK = ["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--seed", "7",
        "--calibration", "tests/data/calibration/tabletop_eye_to_hand.yaml", "--quiet"]

pytestmark = [pytest.mark.sim, pytest.mark.slow]


@pytest.fixture(scope="module")
def busy() -> Iterator[None]:
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(os.cpu_count() or 2)]
    try:
        yield
    finally:
        for proc in loops:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def two_runs(busy: None, tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("load")
    logs = [folder / f"pick_{k}.mcap" for k in (1, 2)]
    procs = [subprocess.Popen([*BT, *PICK, "--log", str(log)], cwd=REPO, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for log in logs]
    outputs = [proc.communicate(timeout=600) for proc in procs]
    for proc, (out, err) in zip(procs, outputs, strict=True):
        assert proc.returncode == 0, out + err
    return logs


def test_the_same_seeded_pick_twice_under_load_has_one_fingerprint(two_runs: list[Path]) -> None:
    a, b = (fingerprint_of_log(open_log(log)) for log in two_runs)
    assert a.final_objects, "the result holds the final object poses"
    assert a.first_difference(b) is None
    assert a.digest == b.digest


def test_a_run_recorded_under_load_resimulates_under_load(two_runs: list[Path]) -> None:
    proc = subprocess.run([*BT, "replay", str(two_runs[0]), "--resim", "--json"], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    report = json.loads(proc.stdout)
    assert report["reproduced"] is True
    assert report["fingerprint"]["first_difference"] is None
    assert report["fingerprint"]["recorded"] == report["fingerprint"]["new"]


def test_the_logs_text_messages_do_not_depend_on_the_machines_speed(two_runs: list[Path]) -> None:
    # issue 27: the end frame's log line said how many ms its read-back took, so two runs of one seed wrote
    # different bytes; the log says how many ticks later now (wall times go to Python's log only)
    a, b = ([(m["stamp_ns"], m["level"], m["name"], m["message"]) for m in open_log(log).logs] for log in two_runs)
    assert any("end frame" in m[3] for m in a)
    assert a == b
