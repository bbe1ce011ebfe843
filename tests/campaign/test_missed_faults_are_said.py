"""A campaign says when a fault hit an object the tree never touched (issue 43, finding 2): an A/B campaign "showed"
a tree without recovery to be robust to nudges, its rows saying `faults_fired: 1`, success, while each push had
hit an object the tree never worked on. `eval run`'s progress line and `eval report` now say so, from the row's
`faults` column; a row written before that column existed, or whose push hit the grasped object, says nothing."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

from rich.console import Console

from bt_grasp.campaign import report
from bt_grasp.campaign.runner import Progress
from bt_grasp.cli.eval_cmd import progress_printer


def _row(seed: int, faults: list[dict[str, Any]] | None) -> dict[str, Any]:
    row: dict[str, Any] = {
        "campaign": "c", "episode": f"e{seed}", "tree": "../trees/pick.xml", "scene": "stack", "seed": seed,
        "fault_plan": "object_nudge", "params": {}, "success": True, "failure_reason": None, "failed_leaf": None,
        "ticks": 1381, "sim_time_s": 13.81, "episode_wall_s": 3.0, "retries": {}, "retries_total": 0,
        "worker": "host:1", "mcap": None, "faults_fired": 1,
    }
    if faults is not None:
        row["faults"] = faults
    return row


def _push(target: str, touched: bool) -> dict[str, Any]:
    return {"label": "object_nudge@PlanGrasp#1", "kind": "object_nudge", "tick": 1, "leaf": "PlanGrasp",
            "target": target, "target_touched": touched}


def _page(tmp_path: Path, rows: list[dict[str, Any]]) -> str:
    results = tmp_path / "c.jsonl"
    results.write_text("".join(json.dumps(r) + "\n" for r in rows))
    report.build_report(results, tmp_path / "report.html")
    page = (tmp_path / "report.html").read_text()
    return page[page.index("<body"):]


def test_the_report_counts_the_episodes_whose_push_hit_an_untouched_object(tmp_path: Path) -> None:
    rows = [_row(0, [_push("blue_box", False)]), _row(1, [_push("red_box", True)]), _row(2, None),
            _row(3, [_push("blue_box", False)])]
    body = _page(tmp_path, rows)
    assert "2 episode(s): a fault pushed an object the tree never touched" in body, body[:2000]


def test_a_report_without_such_a_push_says_nothing_of_it(tmp_path: Path) -> None:
    body = _page(tmp_path, [_row(0, [_push("red_box", True)]), _row(1, None), _row(2, [])])
    assert "never touched" not in body


def test_the_progress_line_names_the_object_the_tree_never_touched() -> None:
    out = io.StringIO()
    show = progress_printer(Console(file=out, width=400, color_system=None))
    progress = Progress(total=2, already=0, done=1, successes=1, finished=1)
    show(progress, _row(0, [_push("blue_box", False)]))  # type: ignore[arg-type]
    show(progress, _row(1, [_push("red_box", True)]))  # type: ignore[arg-type]
    first, second = out.getvalue().splitlines()
    assert "ok (a fault pushed blue_box: the tree never touched it)" in first, first
    assert "never touched" not in second, second
