"""The campaign report's figures as drawn (issue 43, finding 9): each test looks at the rendered figure.

- No legend covers a label, a bar or an error bar (the success figure's legend sat on its "n/N" labels and error
  bars, the failure reasons' and the comparison's on their bars).
- The wall-time plot leaves every worker's first episode out, as the docs say, and counts them on its axis, also
  in a campaign so small that every episode was a worker's first (it kept them all then, and said nothing).
"""

from __future__ import annotations

from typing import Any

import pytest

from bt_grasp.campaign import plots
from bt_grasp.campaign.stats import success_rates
from tests.figure_checks import legend_overlaps, texts_cut

TREES = ("pick", "pick_with_recovery")


def _rows(episodes_per_worker: int = 4) -> list[dict[str, Any]]:
    rows = []
    for t, tree in enumerate(TREES):
        for seed in range(4):
            ok = (seed + t) % 3 != 0 and seed != 3  # the last seed fails in both: labels and bars at the right too
            rows.append({
                "campaign": "c", "episode": f"{tree}{seed}", "tree": f"../trees/{tree}.xml", "scene": "tabletop",
                "seed": seed, "fault_plan": "none" if seed % 2 else "frame_drop", "params": {}, "success": ok,
                "failure_reason": None if ok else "NO_DETECTION", "failed_leaf": None if ok else "Perceive",
                "failed_path": None if ok else "PickObject::5/Perceive::9", "ticks": 700 + seed,
                "sim_time_s": 7.0 + seed / 10, "episode_wall_s": 40.0 if seed == 0 else 3.0 + seed / 10,
                "retries": {} if ok else {"PickObject::5/Perceive::9": 1 + seed},
                "retries_total": 0 if ok else 1 + seed,
                "worker": f"host:{(t * 4 + seed) // episodes_per_worker}", "mcap": None,
            })
    return rows


@pytest.mark.parametrize("name", ["success", "failures", "retries", "comparison"])
def test_no_legend_covers_a_label_a_bar_or_an_error_bar(name: str, drawn: list[Any]) -> None:
    rows = _rows()
    if name == "success":
        plots.success_by_group(rows, "c")
    elif name == "failures":
        plots.failure_reasons(rows)
    elif name == "retries":
        plots.retries(rows)
    else:
        other = [{**r, "success": True} for r in rows]
        plots.comparison(success_rates(rows, plots.GROUPS), success_rates(other, plots.GROUPS), ("A: c", "B: d"))
    assert legend_overlaps(drawn[-1]) == []
    assert texts_cut(drawn[-1]) == []


def _wall_times(fig: Any) -> list[float]:
    """The wall times the right-hand panel draws (its boxes' data), whatever the boxes."""
    wall = fig.axes[1]
    drawn = [line.get_xdata() for line in wall.lines]
    return sorted({float(x) for xs in drawn for x in xs})


def test_the_wall_times_leave_out_every_workers_first_episode_and_count_them(drawn: list[Any]) -> None:
    plots.time_distributions(_rows(episodes_per_worker=4))
    wall = drawn[-1].axes[1]
    assert "left out: 2" in wall.get_xlabel()
    assert max(_wall_times(drawn[-1])) < 10  # the 40 s warm-ups are not drawn
    assert texts_cut(drawn[-1]) == []  # the label saying so ran past the figure's edge


def test_a_campaign_whose_every_episode_was_a_workers_first_draws_no_wall_time_and_says_why(
        drawn: list[Any]) -> None:
    rows = _rows(episodes_per_worker=1)  # eight workers, one episode each: every one paid its worker's warm-up
    assert plots.warm_up_rows(rows) == set(range(len(rows)))
    plots.time_distributions(rows)
    wall = drawn[-1].axes[1]
    assert "left out: 8" in wall.get_xlabel(), wall.get_xlabel()
    assert 40.0 not in _wall_times(drawn[-1]), "the warm-ups were drawn after all"
    shown = " ".join(t.get_text() for t in wall.texts)
    assert "every episode" in shown, shown
