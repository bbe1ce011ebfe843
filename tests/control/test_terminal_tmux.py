"""`bt-grasp run --interactive` in a real terminal: tmux runs it, send-keys presses the keys, capture-pane reads
the screen (issue 25, Done when 1 for the terminal). Bad ``--break``/``--interactive`` input is exit 2, one line.

The end-to-end run: trees/pick.xml on the tabletop, ``--break node:Grasp``. Paused before tick 1: ``f`` (break
on failure on), ``s`` (tick 1: Perceive waits for its detections, 0.1 s of simulated time), ``n 10`` (tick 11:
everything up to Approach ran), ``b`` with a bad value (one sentence, nothing
changes), ``b lift_height=0.15``, ``o 0`` (the red box, as Perceive chose), ``x frame_drop``; ``p`` runs to the
breakpoint before Grasp; ``n 5`` steps five ticks; ``q`` stops the run, the log is finished and lists the four
interventions and the stop.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]
SIZE = (150, 42)
#: where the test leaves its screen captures (docs/interactive.md shows them)
CAPTURES = "BT_GRASP_TMUX_CAPTURES"


def _bt(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*BT, *args], capture_output=True, text=True, timeout=300, cwd=REPO, stdin=subprocess.DEVNULL)


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--interactive", "--break", "tick:x"], "--break: 'tick:x': 'x' is not a tick number; expected node:NAME"),
        (["--interactive", "--break", "fail", "--break", "nodes:Grasp"], "--break: 'nodes:Grasp': unknown kind"),
        (["--break", "fail"], "--break: breakpoints need --interactive"),
        (["--interactive"], "--interactive: needs a terminal"),
        (["--interactive", "--resident"], "--interactive: an interactive run cannot be --resident"),
    ],
)
def test_bad_interactive_input_is_exit_2_one_line(args: list[str], fragment: str, tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    proc = _bt("run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--log", str(log), *args)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], proc.stderr
    assert not log.exists()


class Tmux:
    def __init__(self, name: str) -> None:
        self.name = name

    def keys(self, *keys: str) -> None:
        subprocess.run(["tmux", "send-keys", "-t", self.name, *keys], check=True, timeout=10)

    def screen(self) -> str:
        return subprocess.run(["tmux", "capture-pane", "-p", "-t", self.name], check=True, capture_output=True,
                              text=True, timeout=10).stdout

    def wait_for(self, *texts: str, timeout_s: float = 120) -> str:
        deadline = time.monotonic() + timeout_s
        screen = ""
        while time.monotonic() < deadline:
            screen = self.screen()
            if all(t in screen for t in texts):
                return screen
            time.sleep(0.2)
        raise AssertionError(f"timed out waiting for {texts}; the screen:\n{screen}")

    def answer(self, key: str, text: str) -> None:
        self.keys(key)
        self.wait_for("Enter; Esc cancels" if key == "n" else "")
        time.sleep(0.3)
        self.keys("-l", text)
        self.keys("Enter")


@pytest.fixture
def tmux(tmp_path: Path) -> Iterator[Tmux]:
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (tools/setup_system.sh installs it)")
    name = f"bt_grasp_test_{tmp_path.name}"[:60]
    subprocess.run(["tmux", "kill-session", "-t", name], capture_output=True, timeout=10)
    yield Tmux(name)
    subprocess.run(["tmux", "kill-session", "-t", name], capture_output=True, timeout=10)


@pytest.mark.sim
@pytest.mark.real_client
def test_the_terminal_front_end_in_tmux(tmux: Tmux, tmp_path: Path) -> None:
    import os

    log = tmp_path / "interactive.mcap"
    command = " ".join([*BT, "run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--log", str(log),
                        "--break", "node:Grasp", "--max-ticks", "3000"])
    subprocess.run(["tmux", "new-session", "-d", "-s", tmux.name, "-x", str(SIZE[0]), "-y", str(SIZE[1]),
                    f"cd {REPO} && env -u COLUMNS -u LINES {command} --interactive; echo EXIT=$?; sleep 600"],
                   check=True, timeout=10)  # the terminal size is the window's, not one a parent process set
    # a tmux server that already runs other sessions may size a new window its own way: say it again
    subprocess.run(["tmux", "resize-window", "-t", tmux.name, "-x", str(SIZE[0]), "-y", str(SIZE[1])], check=True,
                   timeout=10)
    captures: dict[str, str] = {}
    screen = tmux.wait_for("PAUSED: paused before the first tick", "Perceive  IDLE", "* lift_height = 0.15")
    assert "p pause/continue" in screen and "q quit" in screen
    captures["start"] = screen
    tmux.keys("f")
    tmux.wait_for("break on failure: on")
    tmux.keys("s")
    screen = tmux.wait_for("tick 1 ", "stepped to tick 1")
    assert "Perceive  RUNNING" in screen  # the frame is taken; its detections reach the tree 0.1 s later
    tmux.answer("n", "10")
    screen = tmux.wait_for("tick 11 ", "stepped to tick 11", "0: red at")
    assert "Perceive  SUCCESS" in screen and "Approach  RUNNING" in screen
    tmux.answer("b", "lift_height=high")
    screen = tmux.wait_for("does not fit")
    assert "interventions: 0" in screen
    tmux.answer("b", "lift_height=0.15")
    tmux.wait_for("interventions: 1", "tick 11: lift_height = 0.15")
    tmux.answer("o", "0")
    tmux.wait_for("interventions: 2", "target = object 0 (red)")
    tmux.answer("x", "frame_drop frames=1")
    tmux.wait_for("interventions: 3", "frame_drop")
    tmux.keys("p")
    screen = tmux.wait_for("PAUSED: before Grasp", timeout_s=300)
    assert "Approach  SUCCESS" in screen and "Grasp  IDLE" in screen
    captures["breakpoint"] = screen
    tmux.answer("n", "5")
    screen = tmux.wait_for("PAUSED: stepped to tick")
    assert "Grasp  RUNNING" in screen
    tmux.keys("q")
    screen = tmux.wait_for("EXIT=", timeout_s=120)
    captures["end"] = screen
    assert "EXIT=1" in screen and "FAILURE" in screen  # stopped before the lift: the goal is not met
    replay = _bt("replay", str(log))
    assert replay.returncode == 0, replay.stderr
    assert "interventions (4)" in replay.stdout
    for kind in ("set_blackboard", "choose_object", "fire_fault", "stop"):
        assert kind in replay.stdout
    assert "STOPPED" in replay.stdout
    folder = os.environ.get(CAPTURES)
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        for name, text in captures.items():
            (Path(folder) / f"{name}.txt").write_text(text)
