"""The campaign report: Wilson intervals, and a self-contained page that a real headless chromium renders
with every figure decoded and no network request."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.campaign.stats import wilson_interval

REPO = Path(__file__).resolve().parents[2]


def test_wilson_interval_known_values() -> None:
    # closed forms: 0/n -> (0, z^2/(n+z^2)); n/n -> (n/(n+z^2), 1); 5/10 is symmetric about 0.5
    z2 = 1.959963984540054**2
    assert wilson_interval(0, 10) == pytest.approx((0.0, z2 / (10 + z2)))
    assert wilson_interval(10, 10) == pytest.approx((10 / (10 + z2), 1.0))
    lo, hi = wilson_interval(5, 10)
    assert lo + hi == pytest.approx(1.0) and lo == pytest.approx(0.2366, abs=1e-4)
    # in general both bounds solve the score equation (p_hat - p)^2 = z^2 p (1 - p) / n
    for k, n in ((81, 263), (1, 7), (49, 50)):
        for p in wilson_interval(k, n):
            assert (k / n - p) ** 2 == pytest.approx(z2 * p * (1 - p) / n, rel=1e-9)


def _rows(campaign: str, tree: str, success_every: int) -> list[dict[str, Any]]:
    rows = []
    for i, (scene, plan) in enumerate((s, p) for s in ("tabletop", "wide") for p in ("none", "frame_drop")):
        for seed in range(6):
            ok = (seed + i) % success_every != 0
            rows.append(
                {
                    "campaign": campaign,
                    "episode": f"{campaign}{i}{seed}",
                    "tree": f"../trees/{tree}.xml",
                    "scene": scene,
                    "seed": seed,
                    "fault_plan": plan,
                    "params": {"color": "red"},
                    "success": ok,
                    "failure_reason": None if ok else "NO_DETECTION",
                    "failed_leaf": None if ok else "Perceive",
                    "ticks": 700 + seed,
                    "sim_time_s": 7.0 + seed / 10,
                    "episode_wall_s": 3.0 + seed / 5,
                    "retries": {} if ok else {"Perceive": 2},
                    "retries_total": 0 if ok else 2,
                    "mcap": None if ok else f"/logs/{campaign}{i}{seed}.mcap",
                    "environment": {
                        "id": "abc",
                        "cpu_model": "test cpu",
                        "cpu_count": 2,
                        "python": "3.11",
                        "libraries": {"sapien": "3.0.3"},
                    },
                }
            )
    return rows


def _write(path: Path, rows: list[dict[str, Any]]) -> Path:
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return path


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("no chromium on this machine (tools/setup_system.sh installs Debian's)")
    return exe


@pytest.mark.real_client
def test_report_renders_in_headless_chromium(tmp_path: Path) -> None:
    a = _write(tmp_path / "before.jsonl", _rows("before", "pick_with_recovery", 3))
    b = _write(tmp_path / "after.jsonl", _rows("after", "pick_with_recovery", 6))
    out = tmp_path / "report.html"
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "eval", "report", str(a), "--compare", str(b), "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=REPO,
    )
    assert proc.returncode == 0, proc.stderr
    page = out.read_text()
    # self-contained: every resource is inline; nothing to fetch
    assert re.findall(r'(?:src|href)="(?!data:)[^"]*"', page) == []
    assert "http://" not in page and "https://" not in page
    figures = sorted(p.name for p in (tmp_path / "report_figures").iterdir())
    assert figures == ["comparison.png", "failures.png", "retries.png", "success.png", "times.png"]
    assert all((tmp_path / "report_figures" / f).read_bytes().startswith(b"\x89PNG") for f in figures)
    # the numbers the page states: 'before' fails 1 in 3 of 24 episodes: 16 succeed; Wilson interval per group
    assert "24 episodes, 16 succeeded (66.7%)" in page
    assert "episodes ran in both" in page

    exe = _chromium()
    flags = [
        exe,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-extensions",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--virtual-time-budget=5000",
    ]
    dom = subprocess.run([*flags, "--dump-dom", out.as_uri()], capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert 'data-figures-decoded="5/5"' in dom.stdout, "the browser did not decode every figure"
    shot = tmp_path / "shot.png"
    subprocess.run(
        [*flags, "--hide-scrollbars", "--window-size=1100,1400", f"--screenshot={shot}", out.as_uri()],
        capture_output=True,
        timeout=120,
        check=True,
    )
    from matplotlib.image import imread

    pixels = imread(shot)
    assert pixels.shape[:2] == (1400, 1100)
    assert pixels[..., :3].std() > 0.05, "the screenshot is blank"


@pytest.mark.parametrize(("k", "n"), [(0, n) for n in range(1, 60)] + [(n, n) for n in range(1, 60)])
def test_item5_the_interval_always_contains_the_rate_at_0_of_n_and_n_of_n(k: int, n: int) -> None:
    lo, hi = wilson_interval(k, n)
    assert 0.0 <= lo <= k / n <= hi <= 1.0
    assert (lo == 0.0) if k == 0 else (hi == 1.0)


def test_item5_eval_report_on_all_failed_and_all_succeeded_groups_exits_0(tmp_path: Path) -> None:
    from bt_grasp.campaign.report import build_report

    rows = []
    for group, ok in (("tabletop", False), ("wide", True)):  # 0/n and n/n
        for seed in range(7):
            row = _rows("c", "pick", 2)[0]
            row.update(scene=group, seed=seed, episode=f"{group}{seed}", success=ok,
                       failure_reason=None if ok else "NO_DETECTION", failed_leaf=None if ok else "Perceive")
            rows.append(row)
    results = _write(tmp_path / "r.jsonl", rows)
    written = build_report(results, tmp_path / "report.html", compare=results)
    assert (tmp_path / "report.html").exists() and written


def test_dollar_signs_in_names_do_not_start_mathtext_in_the_report(tmp_path: Path) -> None:
    """Issue 22 (weak items): a leaf or scene named with '$...$' crashed the matplotlib figures."""
    from bt_grasp.campaign.report import build_report

    rows = _rows("c", "pick", 3)
    for row in rows:
        row["scene"] = "cost_$\\frac{1}{0$"
        if not row["success"]:
            row["failed_leaf"] = "$\\undefinedcommand{x}$"
            row["retries"] = {"$^$": 1}
    results = _write(tmp_path / "r.jsonl", rows)
    build_report(results, tmp_path / "report.html")
    assert "$\\undefinedcommand{x}$" in (tmp_path / "report.html").read_text()


def test_crafted_numbers_in_a_compared_results_file_are_escaped_in_the_report(tmp_path: Path) -> None:
    """Issue 22 (weak items): seed, ticks and cpu_count went into the HTML unescaped (`--compare` a crafted file)."""
    from bt_grasp.campaign.report import build_report
    from bt_grasp.errors import InputError

    payload = "<script>alert(1)</script>"
    rows = _rows("evil", "pick", 2)
    for row in rows:
        row["environment"]["cpu_count"] = payload  # free-form: shown, escaped
    ok = _write(tmp_path / "ok.jsonl", _rows("ok", "pick", 3))
    evil = _write(tmp_path / "evil.jsonl", rows)
    build_report(evil, tmp_path / "report.html", compare=ok)
    page = (tmp_path / "report.html").read_text()
    assert payload not in page and "&lt;script&gt;" in page
    rows[0]["ticks"] = payload  # a column a report counts with is checked: refused, naming file, line, column
    evil = _write(tmp_path / "evil.jsonl", rows)
    with pytest.raises(InputError, match=r"evil.jsonl:1: 'ticks' is .*, not an integer or null"):
        build_report(evil, tmp_path / "report2.html", compare=ok)
