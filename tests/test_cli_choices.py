"""Typed choices (issue 24): every option whose set of values is fixed is an enum, so ``--help`` lists the values,
the shell completes them and the parser refuses a wrong one in the one error format. On main as it was these were
free strings (`run --goal`, `bench plan --planner`, `bench tasks --task`, `bench follow --mounts/--pick-mount`,
`scene render --mount`): nothing to complete, and each command checked them (or not) in its own words."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[1]
PREFIX = "bt-grasp: error: "
MOUNTS = ["eye-to-hand", "eye-in-hand"]
TASKS = ["pick", "pick_and_place", "stack", "sort_by_color", "clear_table", "clear_household"]
PLANNERS = ["RRTConnect", "RRT", "RRTstar", "InformedRRTstar", "SORRTstar", "BITstar", "AORRTC"]


def _complete(words: str) -> list[str]:
    env = {**os.environ, "_BT_GRASP_COMPLETE": "complete_bash", "COMP_WORDS": words,
           "COMP_CWORD": str(len(words.split()) - (0 if words.endswith(" ") else 1))}
    done = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main"], env=env, cwd=REPO, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


# (the words typed before the value, the values completed, a wrong value's argv)
CASES = [
    ("bt-grasp run trees/pick.xml --scene scenes/tabletop.yaml --goal ", ["pick", "clear"],
     ["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--goal", "lift"]),
    ("bt-grasp bench plan --planner ", PLANNERS, ["bench", "plan", "--planner", "Nope"]),
    ("bt-grasp bench tasks --task ", TASKS, ["bench", "tasks", "--task", "juggle"]),
    ("bt-grasp bench follow --pick-mount ", MOUNTS, ["bench", "follow", "--pick-mount", "wrist"]),
    ("bt-grasp bench follow --mounts ", MOUNTS, ["bench", "follow", "--mounts", "wrist"]),
    ("bt-grasp scene render scenes/tabletop.yaml --mount ", MOUNTS,
     ["scene", "render", "scenes/tabletop.yaml", "--mount", "wrist"]),
]


@pytest.mark.parametrize(("words", "choices", "bad"), CASES, ids=[c[2][c[2].index(next(
    a for a in c[2] if a.startswith("--") and a != "--scene"))] for c in CASES])
def test_a_fixed_set_is_completed_and_a_wrong_value_refused_in_one_line(
    words: str, choices: list[str], bad: list[str], capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(REPO)
    assert _complete(words) == choices
    assert main(bad) == 2  # refused by the parser: nothing ran (no simulator, no planner)
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    flag, value = bad[-2], bad[-1]
    assert captured.out == "" and len(lines) == 1, captured
    assert lines[0].startswith(f"{PREFIX}Invalid value for '{flag}'") and f"'{value}' is not one of" in lines[0]
    assert all(f"'{c}'" in lines[0] for c in choices), lines[0]  # the answer names every choice


@pytest.mark.parametrize(("command", "flag", "choices"), [
    (["run"], "--goal", ["pick", "clear"]),
    (["bench", "plan"], "--planner", PLANNERS),
    (["bench", "tasks"], "--task", TASKS),
    (["bench", "follow"], "--mounts", MOUNTS),
    (["scene", "render"], "--mount", MOUNTS),
], ids=["run-goal", "bench-plan-planner", "bench-tasks-task", "bench-follow-mounts", "scene-render-mount"])
def test_help_lists_the_choices(command: list[str], flag: str, choices: list[str],
                                capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    assert main([*command, "--help"]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines() if f" {flag} " in line)
    assert "|".join(choices) in line, line


def test_mounts_still_take_a_comma_separated_list_and_complete_after_a_comma() -> None:
    from bt_grasp.cli.choices import MOUNT_LIST

    assert MOUNT_LIST(" eye-in-hand , eye-to-hand,") == "eye-in-hand,eye-to-hand"  # as `--mounts a,b` was split
    with pytest.raises(ValueError, match="'wrist' is not one of"):
        MOUNT_LIST("eye-to-hand,wrist")
    with pytest.raises(ValueError, match="one or more"):
        MOUNT_LIST(" , ")
    assert _complete("bt-grasp bench follow --mounts eye-to-hand,") == ["eye-to-hand,eye-in-hand"]


def test_each_enum_is_the_set_its_source_defines() -> None:
    """The CLI keeps the values literal (--help imports no planner or task code): they must not drift."""
    from bt_grasp.bench.follow import SCENES
    from bt_grasp.bench.tasks import TASKS as tasks
    from bt_grasp.cli.choices import MOUNT_LIST, GoalChoice, PlannerChoice, TaskChoice
    from bt_grasp.interfaces import Mount
    from bt_grasp.motion.planner import PLANNERS as planners
    from bt_grasp.scene.run_goal import COMMAND_LINE_KINDS

    assert [g.value for g in GoalChoice] == list(COMMAND_LINE_KINDS)
    assert [p.value for p in PlannerChoice] == list(planners) == PLANNERS
    assert [t.value for t in TaskChoice] == [t.name for t in tasks] == TASKS
    assert list(MOUNT_LIST.choices) == [m.value for m in Mount] == list(SCENES) == MOUNTS
