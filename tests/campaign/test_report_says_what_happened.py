"""The campaign report says what happened (issue 24): one test per defect, each failing on the code before.

Counts on integer axes (fractional ticks before), bar colours that mean what the legend says (the retried
leaves were drawn in the first tree's colour, the success bars had no legend), each worker's first episode
(its warm-up) kept out of the wall-time plot (an outlier before), and no self-test text on the page ("figures
not decoded (the page was not opened in a browser)" before).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from matplotlib.colors import to_hex

from bt_grasp.campaign import plots, report

TREES = ("pick", "pick_with_recovery")


def _rows() -> list[dict[str, Any]]:
    rows = []
    for t, tree in enumerate(TREES):
        for seed in range(4):
            ok = (seed + t) % 3 != 0
            rows.append({
                "campaign": "c", "episode": f"{tree}{seed}", "tree": f"../trees/{tree}.xml", "scene": "tabletop",
                "seed": seed, "fault_plan": "none", "params": {}, "success": ok,
                "failure_reason": None if ok else "NO_DETECTION", "failed_leaf": None if ok else "Perceive",
                "failed_path": None if ok else "PickObject::5/Perceive::9", "ticks": 700 + seed,
                "sim_time_s": 7.0 + seed / 10,
                # worker w0 ran first and paid its warm-up: 40 s against about 3 s for the steady episodes
                "episode_wall_s": 40.0 if (t, seed) == (0, 0) else 3.0 + seed / 10,
                "retries": {} if ok else {"PickObject::5/Perceive::9": 1}, "retries_total": 0 if ok else 1,
                "worker": f"host:{seed % 2}", "mcap": None,
            })
    return rows


@pytest.fixture
def figures(drawn: list[Any]) -> dict[str, Any]:
    """Each plot's matplotlib Figure, caught where it is turned into PNG bytes."""
    caught = drawn
    rows = _rows()
    out = {}
    for name, draw in (("success", lambda: plots.success_by_group(rows, "c")),
                       ("failures", lambda: plots.failure_reasons(rows)),
                       ("times", lambda: plots.time_distributions(rows)),
                       ("retries", lambda: plots.retries(rows))):
        draw()
        out[name] = caught[-1]
    return out


def test_counts_are_drawn_on_integer_axes(figures: dict[str, Any]) -> None:
    counted = [("failures", 0, "x"), ("retries", 0, "x"), ("retries", 0, "y"), ("retries", 1, "x")]
    for name, index, axis in counted:
        ax = figures[name].axes[index]
        lo, hi = ax.get_xlim() if axis == "x" else ax.get_ylim()
        ticks = [t for t in (ax.get_xticks() if axis == "x" else ax.get_yticks()) if lo <= t <= hi]
        assert ticks and all(float(t).is_integer() for t in ticks), (name, index, axis, list(ticks))


def _legend_colours(fig: Any) -> dict[str, str]:
    out = {}
    for legend in [ax.get_legend() for ax in fig.axes] + list(fig.legends):  # an axes' legend or the figure's
        if legend is None:
            continue
        for handle, text in zip(legend.legend_handles, legend.get_texts(), strict=True):
            out[to_hex(handle.get_facecolor())] = text.get_text()
    return out


@pytest.mark.parametrize("name", ["success", "failures", "retries"])
def test_every_bar_colour_is_the_legend_colour_of_its_tree(figures: dict[str, Any], name: str) -> None:
    fig = figures[name]
    legend = _legend_colours(fig)
    assert legend, f"{name}: bars coloured by tree and no legend to say which"
    assert sorted(legend.values()) == sorted(TREES)
    for ax in fig.axes:
        for container in ax.containers:
            if not hasattr(container, "patches"):
                continue  # error bars
            for bar in container.patches:
                colour = to_hex(bar.get_facecolor())
                assert colour in legend, f"{name}: a bar in {colour}, a colour the legend does not explain"
                assert container.get_label() == legend[colour], (
                    f"{name}: a bar in {legend[colour]}'s colour counts {container.get_label()!r}")


def test_each_workers_warm_up_is_left_out_of_the_wall_times(figures: dict[str, Any]) -> None:
    wall = figures["times"].axes[1]
    assert wall.get_xlim()[1] < 10, "the first episode's 40 s warm-up is drawn as an outlier"
    label = " ".join(wall.get_xlabel().split())
    assert "left out: 2, each worker's first episode, which pays its warm-up" in label, label
    assert plots.warm_up_rows(_rows()) == {0, 1}  # host:0 and host:1 each ran their first episode there


def test_the_page_shows_no_self_test_text(tmp_path: Path) -> None:
    results = tmp_path / "c.jsonl"
    results.write_text("".join(json.dumps(r) + "\n" for r in _rows()))
    out = tmp_path / "report.html"
    report.build_report(results, out)
    page = out.read_text()
    body = page[page.index("<body"):]
    assert "decoded" not in body, "a self-test line is shown to the reader"
    assert "PickObject::5/Perceive::9" in body  # failed episodes name the leaf by its path
