"""A live run driven from the real Foxglove Studio web build (`bt-grasp run ... --live PORT --control`), through
the stock panels of the shipped control layout, as an operator would: typing values into the Parameters panel's
editors and pressing the Publish panel's buttons (control_probe.cjs). The run starts paused; paced at 5 ticks
per wall second (``--realtime 0.05``) the pick lasts ~5 minutes, far longer than the test.

Step by step (what each answer proves):
  paused before tick 1              the run waits for the viewer
  breakpoints ["tick:3"] + Resume   a breakpoint set from the panel, the Publish panel's command: holds after tick 3
  run.paused false, then true       running again, then paused from the panel: the tick and the simulated time
                                    stand still for 4 s while the viewer keeps being served
  bb.lift_height 0.12               a blackboard edit, applied and answered in run.message
  bb.lift_height "high"             refused by Lift's port: one sentence under Problems, the entry stays 0.12
  choose.object 2, fault.fire       the object choice (blue: entry target) and a fault fired by hand
  Step 1 tick                       one tick more
  run.restart "next"                the episode ends (its log holds the four interventions, source foxglove, at
                                    the ticks they took effect); the next one (seed 1, run-2.mcap) is served on
                                    the same port and Studio reconnects to it, paused before its first tick
  Step 1 tick, Stop run             the second episode runs one tick and ends (exit 1, STOPPED)
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from studio_driver import CACHE, chromium_path, serving, skip_without_browser
from test_foxglove_live import _free_port, _wait_for_port

from bt_grasp.foxglove.layout import control_layout_path
from bt_grasp.recording.reader import open_log

ROOT = Path(__file__).resolve().parents[2]
PROBE = Path(__file__).resolve().parent / "control_probe.cjs"
DOC_IMAGE = ROOT / "docs" / "images" / "interactive-foxglove.png"

pytestmark = [pytest.mark.sim, pytest.mark.slow, pytest.mark.real_client]


def _steps(shot: Path) -> list[dict[str, Any]]:
    def wait(name: str, timeout: float = 60, **until: Any) -> dict[str, Any]:
        return {"op": "wait", "name": name, "until": until, "timeout": timeout}

    def read(label: str) -> dict[str, Any]:
        return {"op": "read", "label": label, "names": ["run.tick", "run.sim_time_s", "run.status", "run.paused",
                                                          "bb.lift_height", "run.message"]}

    return [
        wait("run.status", 180, eq="paused: paused before the first tick"),
        read("start"),
        {"op": "set", "name": "breakpoints", "text": '["tick:3"]'},
        wait("breakpoints", eq=["tick:3"]),
        {"op": "press", "text": "Resume"},  # the Publish panel: {"kind": "resume"} on /control/command
        wait("run.status", has="breakpoint tick:3"),
        read("at breakpoint"),
        {"op": "set", "name": "breakpoints", "text": "[]"},
        {"op": "set", "name": "run.paused", "text": "false"},
        wait("run.tick", gt=8),
        # while the run goes, its parameters change every tick and Studio draws the Parameters panel's rows again,
        # losing what is being typed (r24, idle: 5 tries, none submitted): pause with the Publish panel's button
        {"op": "press", "text": "Pause"},
        wait("run.status", eq="paused: paused (foxglove)"),
        read("paused"),
        {"op": "sleep", "s": 4},
        read("still paused"),
        {"op": "set", "name": "bb.lift_height", "text": "0.12"},
        wait("run.message", has="lift_height = 0.12"),
        {"op": "set", "name": "bb.lift_height", "text": '"high"'},
        wait("run.message", has="does not fit"),
        read("refused"),
        {"op": "set", "name": "choose.object", "text": "2"},
        wait("run.message", has="target = object 2"),
        {"op": "set", "name": "fault.fire", "text": '"frame_drop"'},
        wait("run.message", has="frame_drop"),
        {"op": "problems", "label": "problems"},
        {"op": "press", "text": "Step 1 tick"},
        wait("run.status", has="stepped to tick"),
        read("stepped"),
        {"op": "screenshot", "path": str(shot)},
        # restart with the next seed: a new episode (run-2.mcap) on the same port; Studio reconnects by itself
        {"op": "set", "name": "run.restart", "text": '"next"'},
        wait("run.status", 180, eq="paused: paused before the first tick"),
        read("restarted"),
        {"op": "press", "text": "Step 1 tick"},
        wait("run.status", eq="paused: stepped to tick 1"),
        {"op": "press", "text": "Stop run"},
        {**wait("run.status", eq="finished"), "or_gone": True},  # the run then ends: checked below
    ]


def test_foxglove_panels_drive_a_live_run(tmp_path: Path) -> None:
    skip_without_browser()
    port = _free_port()
    log = tmp_path / "run.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(ROOT / "trees/pick.xml"),
         "--scene", str(ROOT / "scenes/tabletop.yaml"), "--live", str(port), "--control", "--realtime", "0.05",
         "--max-ticks", "3000", "--log", str(log)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1", "COLUMNS": "200"},
    )
    shot = tmp_path / "control.png"
    steps = tmp_path / "steps.json"
    steps.write_text(json.dumps(_steps(shot)))
    out = tmp_path / "probe.json"
    try:
        _wait_for_port(port, proc, 120)
        with serving(tmp_path, control_layout_path()) as server:
            probe = subprocess.run(
                ["node", str(PROBE), "--url", server.url_for_websocket(), "--ws-bridge", f"ws://127.0.0.1:{port}",
                 "--steps", str(steps), "--out", str(out), "--chromium", str(chromium_path()),
                 "--profile", str(tmp_path / "chromium-profile")],
                capture_output=True, text=True, timeout=480, cwd=CACHE,
                env={**os.environ, "NODE_PATH": str(CACHE / "node_modules")})
        report = json.loads(out.read_text()) if out.is_file() else {}
        if probe.returncode != 0 or "failure" in report:
            proc.kill()  # a paused run waits for ever: no use waiting for it
        stdout, stderr = proc.communicate(timeout=120)  # Stop run ends it: the log is finished
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert probe.returncode == 0 and report, probe.stderr[-3000:]
    assert "failure" not in report, (f"{report.get('failure')}\nseen: {json.dumps(report['seen'])[-3000:]}\n"
                                     f"run: {stderr[-2000:]}")
    assert report["errors"] == []
    reads = {s["label"]: s["values"] for s in report["seen"] if s["op"] == "read"}
    assert reads["start"]["run.tick"] == 0 and reads["start"]["run.paused"] is True
    assert reads["at breakpoint"]["run.tick"] == 3
    paused, still = reads["paused"], reads["still paused"]
    assert paused["run.tick"] > 8 and paused["run.paused"] is True
    # 4 s at 5 ticks a second would be ~20 ticks: paused, neither the tick nor the simulated time moved
    assert (still["run.tick"], still["run.sim_time_s"]) == (paused["run.tick"], paused["run.sim_time_s"])
    assert reads["refused"]["bb.lift_height"] == 0.12  # the bad value changed nothing
    assert "does not fit" in reads["refused"]["run.message"] and "goes on unchanged" in reads["refused"]["run.message"]
    problems = next(s["text"] for s in report["seen"] if s["op"] == "problems")
    assert "blackboard entry 'lift_height' = 'high' does not fit" in problems, problems
    assert reads["stepped"]["run.tick"] == paused["run.tick"] + 1

    assert reads["restarted"]["run.tick"] == 0 and reads["restarted"]["bb.lift_height"] == 0.15  # a new episode
    assert proc.returncode == 1, stderr[-2000:]  # stopped: no pick, judged as it stands
    assert "STOPPED" in stdout and "seed 1" in stdout, stdout
    run = open_log(log)
    assert run.result is not None and run.result["reason"] == "STOPPED" and not run.truncated
    records = [(r["tick"], r["kind"], r["source"]) for r in run.interventions]
    t = paused["run.tick"]
    assert records == [(t, "set_blackboard", "foxglove"), (t, "choose_object", "foxglove"),
                       (t, "fire_fault", "foxglove"), (t + 1, "restart", "foxglove")], run.interventions
    assert run.interventions[0]["command"] == {"kind": "set_blackboard", "key": "lift_height", "value": 0.12}
    assert run.interventions[1]["command"]["choice"] == 2 and "blue" in run.interventions[1]["effect"]
    assert run.interventions[3]["command"] == {"kind": "restart", "seed": "next"}
    assert run.ticks[-1].tick == t + 1
    second = open_log(tmp_path / "run-2.mcap")
    assert [(r["tick"], r["kind"], r["source"]) for r in second.interventions] == [(1, "stop", "foxglove")]
    assert second.result is not None and second.result["reason"] == "STOPPED" and second.result["ticks"] == 1
    if os.environ.get("BT_GRASP_UPDATE_DOC_IMAGES"):
        shutil.copyfile(shot, DOC_IMAGE)
