"""`bt-grasp eval report`: one self-contained HTML page (figures inlined, no network) plus the same PNGs.

The page holds: success rate per tree / scene / fault plan with 95% Wilson intervals, failure reasons, time
distributions, retries, the failed episodes with their MCAP logs, and, given a second results file, a
side-by-side comparison (per group and per paired episode: same scene, seed, fault plan).
"""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.campaign import plots
from bt_grasp.campaign.results import read_report_rows
from bt_grasp.campaign.rows import ReportEnvironment, ReportRow
from bt_grasp.campaign.stats import Rate, success_rates, tree_label
from bt_grasp.errors import InputError
from bt_grasp.files.output_files import check_output_folder, make_output_folder, write_output_file

MAX_FAILURE_ROWS = 200

_CSS = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1100px; color: #1a202c; }
h1 { font-size: 1.6em; } h2 { font-size: 1.2em; margin-top: 1.6em; border-bottom: 1px solid #cbd5e0; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
th, td { border: 1px solid #cbd5e0; padding: 3px 8px; text-align: left; }
th { background: #edf2f7; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
img { max-width: 100%; display: block; margin: 0.5em 0; }
.note { color: #4a5568; font-size: 0.9em; } .warn { color: #c05621; }
code { background: #edf2f7; padding: 0 3px; }
"""

# Runs in the browser that opens the page: records, out of sight, that every figure decoded (a data attribute
# of <body> the browser test reads; nothing is shown to the reader).
_CHECK = """
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
  document.body.setAttribute("data-figures-decoded", ok + "/" + imgs.length);
});
"""


@dataclass(frozen=True)
class Figure:
    name: str  # file stem of its PNG
    title: str
    png: bytes


def _load(path: Path) -> list[ReportRow]:
    rows = read_report_rows(path)
    if not rows:
        raise InputError(path, "holds no finished episode yet")
    return rows


def _name(rows: Sequence[ReportRow], path: Path) -> str:
    names = sorted({str(r.get("campaign", path.stem)) for r in rows})
    return ", ".join(names)


def _pct(x: float) -> str:
    return f"{100 * x:.1f}%"


def _rates_table(rates: Sequence[Rate], columns: Sequence[str]) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = []
    for r in rates:
        lo, hi = r.interval
        cells = "".join(f"<td>{html.escape(g)}</td>" for g in r.group)
        body.append(
            f"<tr>{cells}<td class=num>{r.successes}/{r.n}</td><td class=num>{_pct(r.rate)}</td>"
            f"<td class=num>{_pct(lo)} - {_pct(hi)}</td></tr>"
        )
    return (
        f"<table><tr>{head}<th>successes</th><th>rate</th><th>95% interval (Wilson)</th></tr>"
        + "".join(body)
        + "</table>"
    )


def _failures_table(rows: Sequence[ReportRow]) -> str:
    failed = [r for r in rows if not r["success"]]
    if not failed:
        return "<p>No episode failed.</p>"
    out = [
        "<table><tr><th>tree</th><th>scene</th><th>seed</th><th>fault plan</th><th>reason</th><th>leaf</th>"
        "<th>ticks</th><th>replay</th></tr>"
    ]
    for r in sorted(failed, key=lambda r: (tree_label(r), r["scene"], r["fault_plan"], r["seed"]))[:MAX_FAILURE_ROWS]:
        replay = f"<code>bt-grasp replay {html.escape(str(r['mcap']))}</code>" if r.get("mcap") else "(log not kept)"
        out.append(
            f"<tr><td>{html.escape(tree_label(r))}</td><td>{html.escape(str(r['scene']))}</td>"
            f"<td class=num>{html.escape(str(r['seed']))}</td><td>{html.escape(str(r['fault_plan']))}</td>"
            f"<td>{html.escape(str(r['failure_reason']))}</td>"
            f"<td>{html.escape(str(r.get('failed_path') or r['failed_leaf']))}</td>"
            f"<td class=num>{html.escape(str(r['ticks']))}</td><td>{replay}</td></tr>"
        )
    more = len(failed) - MAX_FAILURE_ROWS
    out.append("</table>" + (f"<p class=note>... and {more} more (see the results file)</p>" if more > 0 else ""))
    return "".join(out)


def _environments(rows: Sequence[ReportRow]) -> str:
    envs: dict[str, ReportEnvironment] = {}
    for r in rows:
        env = r.get("environment") or {}
        envs.setdefault(str(env.get("id", "?")), env)
    parts = []
    for env_id, env in envs.items():
        libs = ", ".join(f"{k} {v}" for k, v in (env.get("libraries") or {}).items() if v)
        parts.append(
            f"<li><code>{html.escape(env_id)}</code>: {html.escape(str(env.get('cpu_model', '?')))}, "
            f"{html.escape(str(env.get('cpu_count', '?')))} cores, Python {html.escape(str(env.get('python', '?')))}; "
            f"{html.escape(libs)}</li>"
        )
    warn = (
        "<p class=warn>These results come from more than one environment: compare them knowingly.</p>"
        if len(envs) > 1
        else ""
    )
    return warn + "<ul>" + "".join(parts) + "</ul>"


def _paired(a: Sequence[ReportRow], b: Sequence[ReportRow], names: tuple[str, str]) -> str:
    """Episodes run in both campaigns on the same scene, seed and fault plan: which ones changed outcome."""

    def key(r: ReportRow) -> tuple[str, int, str, str]:
        return (str(r["scene"]), int(r["seed"]), str(r["fault_plan"]), str(sorted(r.get("params", {}).items())))

    single_a = len({tree_label(r) for r in a}) == 1 and len({tree_label(r) for r in b}) == 1
    if not single_a:
        return "<p class=note>Paired episodes are listed when each campaign runs one tree.</p>"
    by_a, by_b = {key(r): r for r in a}, {key(r): r for r in b}
    common = sorted(set(by_a) & set(by_b))
    gained = [k for k in common if by_b[k]["success"] and not by_a[k]["success"]]
    lost = [k for k in common if by_a[k]["success"] and not by_b[k]["success"]]
    rows = "".join(
        f"<tr><td>{html.escape(k[0])}</td><td class=num>{k[1]}</td><td>{html.escape(k[2])}</td><td>{what}</td></tr>"
        for what, keys in (
            (f"fails in {names[0]}, succeeds in {names[1]}", gained),
            (f"succeeds in {names[0]}, fails in {names[1]}", lost),
        )
        for k in keys[:50]
    )
    return (
        f"<p>{len(common)} episodes ran in both (same scene, seed, fault plan, parameters): "
        f"{len(gained)} fixed and {len(lost)} broken by {html.escape(names[1])}.</p>"
        + (
            f"<table><tr><th>scene</th><th>seed</th><th>fault plan</th><th>change</th></tr>{rows}</table>"
            if rows
            else ""
        )
    )


def missed_faults(rows: Sequence[ReportRow]) -> int:
    """Episodes in which a fault pushed an object the tree never touched (``FaultFiring.missed``)."""
    def missed(row: ReportRow) -> bool:
        faults = row.get("faults")
        return isinstance(faults, list) and any(
            isinstance(f, dict) and f.get("target") is not None and f.get("target_touched") is False for f in faults)

    return sum(1 for row in rows if missed(row))


def figure_folder(out: Path) -> Path:
    """Where a report's figures go: ``<out stem>_figures/`` beside it."""
    return Path(out).with_name(Path(out).stem + "_figures")


def build_report(results: Path, out: Path, compare: Path | None = None) -> list[Path]:
    """Write ``out`` (HTML) and its figures as PNG files in ``<out stem>_figures/``; returns every file written."""
    check_output_folder(figure_folder(out), "--out", inputs=(results, compare))
    rows = _load(results)
    name = _name(rows, results)
    figures = [
        Figure("success", "Success rate per tree / scene / fault plan", plots.success_by_group(rows, name)),
        Figure("failures", "Failure reasons", plots.failure_reasons(rows)),
        Figure("times", "Time distributions", plots.time_distributions(rows)),
        Figure("retries", "Retries", plots.retries(rows)),
    ]
    sections = [
        f"<h2>Success rate per tree, scene and fault plan</h2>"
        f"{_rates_table(success_rates(rows, plots.GROUPS), ['tree', 'scene', 'fault plan'])}",
    ]
    comparison = ""
    if compare is not None:
        other = _load(compare)
        names = (f"A: {name}", f"B: {_name(other, compare)}")
        same_trees = {tree_label(r) for r in rows} == {tree_label(r) for r in other}
        by = plots.GROUPS if same_trees else ("scene", "fault_plan")
        rates_a, rates_b = success_rates(rows, by), success_rates(other, by)
        figures.append(Figure("comparison", f"{names[0]} vs {names[1]}", plots.comparison(rates_a, rates_b, names)))
        comparison = (
            f"<h2>Comparison: {html.escape(names[0])} vs {html.escape(names[1])}</h2>"
            f"<p class=note>B's results file: {html.escape(str(compare))} ({len(other)} episodes).</p>"
            f"<h3>{html.escape(names[0])}</h3>{_rates_table(rates_a, by)}"
            f"<h3>{html.escape(names[1])}</h3>{_rates_table(rates_b, by)}"
            f"{_paired(rows, other, names)}"
        )
    out = Path(out)
    fig_dir = make_output_folder(figure_folder(out), "--out", inputs=(results, compare))
    written = [write_output_file(fig_dir / f"{fig.name}.png", fig.png, "--out") for fig in figures]
    images = {
        f.name: f'<img alt="{html.escape(f.title)}" src="data:image/png;base64,{base64.b64encode(f.png).decode()}">'
        for f in figures
    }
    ok = sum(1 for r in rows if r["success"])
    missed = missed_faults(rows)
    warn = (f"<p class=warn>{missed} episode(s): a fault pushed an object the tree never touched, not one it "
            "grasped (the results file's <code>faults</code> column names the object; to push the object the tree "
            "grasps, name it in the fault plan: <code>params.object</code>).</p>") if missed else ""
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>bt_grasp campaign report: {html.escape(name)}</title>
<style>{_CSS}</style><script>{_CHECK}</script></head>
<body>
<h1>Campaign report: {html.escape(name)}</h1>
<p>{len(rows)} episodes, {ok} succeeded ({_pct(ok / len(rows))}); results file {html.escape(str(results))}.
Success is judged by physics (the simulator's ground truth, read only by the judge).</p>
{warn}{images["success"]}
{sections[0]}
<h2>Failure reasons</h2>{images["failures"]}
<h2>Failed episodes</h2>{_failures_table(rows)}
<h2>Time distributions</h2>{images["times"]}
<h2>Retries</h2>{images["retries"]}
{comparison}{images.get("comparison", "")}
<h2>Environments</h2>{_environments(rows)}
</body></html>
"""
    write_output_file(out, page, "--out", example="report.html")
    return [out, *written]
