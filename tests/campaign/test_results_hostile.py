"""Issue 22: a results file is user input. `eval report` on a damaged or hostile one (binary, cut, deep, huge,
wrong types, missing columns, NaN, lone surrogates) exits 2 with one sentence naming the file and the line,
never a traceback, a MemoryError or a hang."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli.main import main

GOOD: dict[str, Any] = {
    "campaign": "c", "episode": "e0", "tree": "trees/pick.xml", "scene": "tabletop", "seed": 0,
    "fault_plan": "none", "params": {"color": "red"}, "success": False, "failure_reason": "NO_DETECTION",
    "failed_leaf": "Perceive", "ticks": 700, "sim_time_s": 7.0, "episode_wall_s": 1.2,
    "retries": {"Perceive": 1}, "retries_total": 1, "mcap": None,
    "environment": {"id": "abc", "cpu_model": "x", "cpu_count": 2, "python": "3.11", "libraries": {}},
}


def _line(**changes: Any) -> bytes:
    row = {**GOOD, **changes}
    return json.dumps({k: v for k, v in row.items() if v is not _DROP}, allow_nan=True).encode()


_DROP = object()

BAD: dict[str, tuple[bytes, str]] = {
    "binary": (b"\x84\xa0\xff\x00", "not UTF-8 text"),
    "latin1": (_line(campaign="fX").replace(b"fX", b"f\xe9"), "not UTF-8 text"),
    "deep": (b"[" * 100_000 + b"]" * 100_000, "nested too deeply"),
    "digits": (b'{"episode": "h", "seed": ' + b"9" * 5000 + b"}", "not a JSON object"),
    "missing_scene": (_line(scene=_DROP), "no 'scene' column"),
    "missing_wall_time": (_line(episode_wall_s=_DROP), "no 'episode_wall_s' column"),
    "environment_text": (_line(environment="$\\frac{1}{0$"), "'environment' is"),
    "retries_total_text": (_line(retries_total="[/]"), "'retries_total' is"),
    "retries_total_huge": (_line(retries_total=10**12), "'retries_total' is"),
    "retries_not_counts": (_line(retries={"Perceive": "x"}), "'retries' is"),
    "nan_time": (_line(sim_time_s=float("nan")), "'sim_time_s' is NaN, not a finite number"),
    "nan_seed": (_line(seed=float("nan")), "'seed' is NaN, not an integer"),
    "success_text": (_line(success="yes"), "'success' is"),
    "lone_surrogate": (_line(failed_leaf="\udcff"), "not valid Unicode"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_hostile_results_row_is_one_sentence_naming_file_and_line(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    line, problem = BAD[name]
    results = tmp_path / "hostile.jsonl"
    results.write_bytes(_line() + b"\n" + line + b"\n")
    code = main(["eval", "report", str(results), "--out", str(tmp_path / "r.html")])
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if x.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert "hostile.jsonl:2:" in lines[0] and problem in lines[0], lines[0]
    assert not (tmp_path / "r.html").exists()


def test_the_checked_rows_still_make_a_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    results = tmp_path / "ok.jsonl"
    results.write_bytes(_line() + b"\n" + _line(episode="e1", seed=1, success=True, failure_reason=None,
                                                 failed_leaf=None, retries={}, retries_total=0) + b"\n")
    code = main(["eval", "report", str(results), "--out", str(tmp_path / "r.html")])
    assert code == 0, capsys.readouterr().err
    assert "2 episodes, 1 succeeded" in (tmp_path / "r.html").read_text()


@pytest.mark.parametrize("shape", ["many_trees", "many_groups_compared", "retries_at_the_limit"])
def test_item3_a_results_file_with_thousands_of_groups_is_drawn_in_seconds(shape: str, tmp_path: Path) -> None:
    """Found by the pre-review attack: an 8.7 MB results file naming 20,000 trees kept `eval report` drawing for
    more than ten minutes and took 4.8 GB (one bar, legend entry and box per tree; 2,000 trees took 65-130 s a
    figure). Figures now draw at most MAX_TREES_DRAWN trees and MAX_GROUPS_DRAWN groups; the tables list all."""
    import time

    from bt_grasp.campaign.plots import MAX_GROUPS_DRAWN

    if shape == "retries_at_the_limit":
        rows = [_line(episode=f"e{i}", retries_total=10_000 if i == 0 else i % 3) for i in range(200)]
    else:
        rows = [_line(episode=f"e{i}", tree=f"trees/t{i}.xml", scene=f"s{i % 7}", failed_leaf=f"L{i}")
                for i in range(3000)]
    results = tmp_path / "r.jsonl"
    results.write_bytes(b"\n".join(rows) + b"\n")
    args = ["eval", "report", str(results), "--out", str(tmp_path / "r.html")]
    if shape == "many_groups_compared":
        args += ["--compare", str(results)]
    t0 = time.monotonic()
    assert main(args) == 0
    assert time.monotonic() - t0 < 90  # under load; each figure took minutes before
    page = (tmp_path / "r.html").read_text()
    if shape != "retries_at_the_limit":
        assert "t2999" in page  # the figures draw MAX_GROUPS_DRAWN groups; the page's tables still list every one
        assert MAX_GROUPS_DRAWN < 3000


# -- issue 42, finding 7 ------------------------------------------------------------------------------------------
def _report(results: Path, out: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, list[str]]:
    code = main(["eval", "report", str(results), "--out", str(out)])
    err = capsys.readouterr().err
    return code, [x for x in err.splitlines() if x.strip()]


@pytest.mark.parametrize("time_s", [1.7e308, -1.7e308])
def test_finding7_times_far_past_any_run_are_refused_in_one_sentence(time_s: float, tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """Two rows with sim_time_s of +-1.7e308 (finite, so accepted) ended in `ValueError: arange`."""
    results = tmp_path / "times.jsonl"
    results.write_bytes(_line() + b"\n" + _line(episode="e1", sim_time_s=time_s) + b"\n")
    code, lines = _report(results, tmp_path / "r.html", capsys)
    assert code == 2 and len(lines) == 1 and "times.jsonl:2:" in lines[0] and "sim_time_s" in lines[0], lines
    assert not (tmp_path / "r.html").exists()


@pytest.mark.parametrize(("column", "size"), [("failed_leaf", 100 << 10), ("tree", 100 << 10), ("retries", 100 << 10),
                                              ("failed_leaf", 4 << 20)])
def test_finding7_a_field_of_megabytes_is_refused_before_anything_is_drawn(
        column: str, size: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Six complete rows, one naming a 100 MB leaf, took `eval report` past 13 GB and two minutes. A field over
    4,096 characters is refused by its column, a row over 1 MB by its size."""
    import time

    huge = "L" * size
    value: Any = {huge: 1} if column == "retries" else huge
    results = tmp_path / "huge.jsonl"
    results.write_bytes(b"\n".join([_line(episode=f"e{i}", seed=i) for i in range(5)]
                                   + [_line(episode="e5", seed=5, **{column: value})]) + b"\n")
    start = time.monotonic()
    code, lines = _report(results, tmp_path / "r.html", capsys)
    assert code == 2 and len(lines) == 1 and "huge.jsonl:6:" in lines[0], lines
    assert (column in lines[0]) if size < 1 << 20 else ("a row of" in lines[0]), lines[0]
    assert time.monotonic() - start < 10 and len(lines[0]) < 400


def test_finding7_the_report_s_figure_folder_is_never_one_of_its_inputs(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    """Results saved as X_figures/success.png were overwritten by the report's own figure."""
    figures = tmp_path / "X_figures"
    figures.mkdir()
    results = figures / "success.png"
    content = _line() + b"\n"
    results.write_bytes(content)
    code, lines = _report(results, tmp_path / "X.html", capsys)
    assert code == 2 and len(lines) == 1 and "X_figures" in lines[0], lines
    assert results.read_bytes() == content and not (tmp_path / "X.html").exists()
    other = tmp_path / "ok.jsonl"
    other.write_bytes(content)
    code = main(["eval", "report", str(other), "--out", str(tmp_path / "X.html"), "--compare", str(results)])
    assert code == 2 and results.read_bytes() == content
