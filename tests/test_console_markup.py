"""Issue 22, item 4: Rich markup in names from a user's files prints as text and never breaks the summary or
a campaign's progress lines."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from bt_grasp.cli.eval_cmd import progress_printer
from bt_grasp.cli.run_cmd import print_summary
from bt_grasp.episode import EpisodeResult
from bt_grasp.episode.instruments import PlanningStats
from bt_grasp.episode.result import Judged
from bt_grasp.scene.goals import PickGoal

HOSTILE = ["[/]", "[link=https://example.invalid]x[/link]", "[bold]", "[/red]"]


def _result(name: str) -> EpisodeResult:
    goal = PickGoal(kind="pick")
    return EpisodeResult(
        success=False, tree_status="FAILURE", reason=name, failed_leaf=name, ticks=3, sim_time_s=0.03,
        wall_time_s=0.1, retries={name: 2}, seed=0, goal=goal, log=f"/tmp/{name}.mcap",
        judged=Judged(goal=goal, success=False, failed_condition=name, conditions=((name, False, name),)),
        planning=PlanningStats(calls=0, pose_calls=0, wall_s=0.0),
    )


@pytest.mark.parametrize("name", HOSTILE)
def test_item4_the_run_summary_prints_markup_in_names_as_text(name: str) -> None:
    out = io.StringIO()
    print_summary(Console(file=out, width=400, color_system=None), _result(name))
    text = out.getvalue()
    assert f"leaf: {name}" in text and f"{name} x2" in text


@pytest.mark.parametrize("name", HOSTILE)
def test_item4_campaign_progress_lines_print_markup_in_names_as_text(name: str) -> None:
    from bt_grasp.campaign.runner import Progress

    out = io.StringIO()
    show = progress_printer(Console(file=out, width=400, color_system=None))
    row = {"success": False, "failure_reason": name, "failed_leaf": name, "tree": f"{name}.xml", "scene": name,
           "seed": 1, "fault_plan": name}
    show(Progress(total=2, already=0), row)
    assert f"({name})" in out.getvalue()


def test_item4_summary_json_is_written_before_anything_is_printed() -> None:
    source = (Path(__file__).resolve().parents[1] / "bt_grasp/cli/run_cmd.py").read_text()
    assert source.index("write_output_file(summary_json") < source.index("print_summary(Console(), summary)")
