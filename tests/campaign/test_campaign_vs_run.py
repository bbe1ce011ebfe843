"""A campaign's episode and `bt-grasp run` with the same tree, scene, seed and fault plan are the same episode
(issue 43, finding 2): the same blackboard defaults (campaigns put `color: red` on the blackboard by default, `run`
does not), so the same fault targets, ticks and outcome; a push on an object the tree never touches says so.

The wide check (every shipped task x every shipped fault plan x two seeds) is `python tools/campaign_vs_run.py OUT`;
here pick and stack with object_nudge, frame_drop and gripper_slip at seed 0, through the same comparison
(``facts``: ticks, outcome, each fault's firing and target, every object's final pose): the campaign's episodes as
its workers run them (``Worker`` on the warm backend, in this process), `run`'s through its command line."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from bt_grasp.campaign.spec import load_campaign
from bt_grasp.campaign.worker import KeepLogs, Worker
from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
TASKS = {"pick": ("trees/pick.xml", "scenes/tabletop.yaml"), "stack": ("trees/stack.xml", "scenes/stack.yaml")}
PLANS = ("object_nudge", "frame_drop", "gripper_slip")
MAX_TICKS = 6000


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("campaign_vs_run", REPO / "tools" / "campaign_vs_run.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


TOOL = _tool()


def test_a_campaign_episode_starts_from_runs_blackboard(tmp_path: Path) -> None:
    """No `blackboard` key: the campaign's episode gets exactly `bt-grasp run`'s blackboard (no `color: red` added);
    a parameter set goes over it as `--set` does."""
    campaign = tmp_path / "c.yaml"
    campaign.write_text(f"name: c\ntrees: [{REPO / 'trees/stack.xml'}]\nscenes: [{REPO / 'scenes/stack.yaml'}]\n"
                        "seeds: [0]\n")
    (episode,) = load_campaign(campaign, check_inputs=False).episodes()
    assert dict(episode.request.blackboard) == {"lift_height": 0.15}  # what `run` puts there: no colour
    from bt_grasp.episode.request import run_blackboard

    assert dict(episode.request.blackboard) == run_blackboard()
    campaign.write_text(campaign.read_text() + "blackboard: [{color: blue}]\n")
    (episode,) = load_campaign(campaign, check_inputs=False).episodes()
    assert dict(episode.request.blackboard) == run_blackboard({"color": "blue"})


def _campaign_rows(folder: Path, tree: str, scene: str, plans: list[str]) -> dict[str, dict[str, Any]]:
    """The campaign's episodes as its workers run them: a row per fault plan."""
    campaign = folder / "campaign.yaml"
    campaign.write_text(json.dumps({"name": "c", "trees": [str(REPO / tree)], "scenes": [str(REPO / scene)],
                                    "seeds": [0], "fault_plans": plans, "max_ticks": MAX_TICKS}))
    from bt_grasp.campaign.backend import warm_backend

    worker = Worker(warm_backend, folder / "logs", KeepLogs.NONE)
    return {episode.fault_plan: dict(worker.run(episode)) for episode in load_campaign(campaign).episodes()}


def _run_summary(folder: Path, tree: str, scene: str, plan: str) -> dict[str, Any]:
    summary = folder / f"run-{Path(plan).stem}.json"
    code = main(["run", str(REPO / tree), "--scene", str(REPO / scene), "--seed", "0", "--faults", plan,
                 "--max-ticks", str(MAX_TICKS), "--summary-json", str(summary), "--quiet"])
    assert code in (0, 1)
    loaded: dict[str, Any] = json.loads(summary.read_text())
    return loaded


@pytest.mark.sim
@pytest.mark.parametrize("task", sorted(TASKS))
def test_campaign_and_run_agree_episode_for_episode(task: str, tmp_path: Path) -> None:
    tree, scene = TASKS[task]
    plans = [str(REPO / "faults" / f"{p}.yaml") for p in PLANS]
    rows = _campaign_rows(tmp_path, tree, scene, plans)
    for plan in plans:
        row, summary = rows[Path(plan).stem], _run_summary(tmp_path, tree, scene, plan)
        assert TOOL.differences(TOOL.facts(row), TOOL.facts(summary)) == [], (task, plan)
        assert summary["faults_fired"] >= 1 and summary["faults"], (task, plan)  # every plan fired, and says where


@pytest.mark.sim
def test_a_push_on_an_object_the_tree_never_touches_says_so(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                            ) -> None:
    """The issue's case: the object a nudge hits is the first of the blackboard colour's (no colour on a scene with a
    declared goal) else the scene's first. On the stack scene with the blue box written first, `run` pushes the blue
    box, which the tree never touches (it grasps the red one and sets it down on the blue one), and says so; the
    campaign's episode starts from the same blackboard (it pushed the red box, with its `color: red`)."""
    text = (REPO / "scenes/stack.yaml").read_text()
    red, blue = text.index("  - name: red_box"), text.index("  - name: blue_box")
    end = text.index("goal:")
    scene = tmp_path / "stack_blue_first.yaml"
    scene.write_text(text[:red] + text[blue:end] + text[red:blue] + text[end:])
    (tmp_path / "tabletop.calibration.yaml").write_bytes((REPO / "scenes/tabletop.calibration.yaml").read_bytes())
    plan = str(REPO / "faults/object_nudge.yaml")
    campaign = tmp_path / "c.yaml"
    campaign.write_text(json.dumps({"name": "c", "trees": [str(REPO / "trees/stack.xml")], "scenes": [str(scene)],
                                    "seeds": [0], "fault_plans": [plan]}))
    (episode,) = load_campaign(campaign).episodes()
    code = main(["run", str(REPO / "trees/stack.xml"), "--scene", str(scene), "--faults", plan, "--max-ticks",
                 str(MAX_TICKS), "--summary-json", str(tmp_path / "run.json"), "--quiet"])
    printed = capsys.readouterr().out
    summary = json.loads((tmp_path / "run.json").read_text())
    (firing,) = summary["faults"]
    assert (firing["target"], firing["target_touched"]) == ("blue_box", False)
    assert "the tree never touched blue_box" in " ".join(printed.split()), printed
    from bt_grasp.episode.request import run_blackboard

    assert dict(episode.request.blackboard) == run_blackboard()  # no colour: the campaign pushes the blue box too
    assert code == 1  # the blue box moved from where the tree had seen it: the red box was not stacked on it
