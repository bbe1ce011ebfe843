"""`bt-grasp replay LOG --report report.html`: one self-contained page about one run (no network needed).

The page holds: the summary; the tree as it ended, each node with its final status, attempts, failures and
retries; a Gantt of the leaves' statuses over simulated time; every failure with its reason, where it
propagated and what ran next (the recovery); injected faults; joint-angle and gripper-opening plots; the
camera frames with the detected boxes drawn in. Figures are PNGs embedded as data URIs (and written to
``png_dir`` too when given).
"""

from __future__ import annotations

import base64
import html
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np
from google.protobuf.message import Message
from numpy.typing import NDArray

from bt_grasp.files.json_types import JsonValue
from bt_grasp.files.output_files import make_output_folder, write_output_file
from bt_grasp.geometry import make_T
from bt_grasp.recording import replay, report_figures, topics
from bt_grasp.recording.attempt_view import attempt_rows, attempts_html
from bt_grasp.recording.interventions import interventions_html
from bt_grasp.recording.reader import RunLog
from bt_grasp.recording.replay_shapes import AnnotatedNode
from bt_grasp.recording.schemas import as_matrix

_CAMERA_FRAMES = ("camera_color_optical_frame", "camera")  # format 2, format 1
_MAX_FRAMES = 12
_T = TypeVar("_T")


@dataclass
class Report:
    html_path: Path
    figures: dict[str, bytes] = field(default_factory=dict)
    pngs: list[Path] = field(default_factory=list)


def _esc(value: object) -> str:
    return html.escape("" if value is None else str(value))


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{_esc(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'


def _badge(status: str) -> str:
    return f'<span class="st st-{_esc(status)}">{_esc(status)}</span>'


# -- data from the log ------------------------------------------------------------------------------------


def _leaf_rows(run: RunLog) -> tuple[list[str], dict[int, str]]:
    """The Gantt's rows: every leaf by its path (its one name: ``tree show``, replay and Foxglove show it too)."""
    leaves = [info for _, info in sorted(run.nodes.items()) if info.is_leaf]
    paths = [info.path or info.name for info in leaves]
    labels = {info.uid: (path if paths.count(path) == 1 else f"{path} #{info.uid}")
              for info, path in zip(leaves, paths, strict=True)}
    return list(labels.values()), labels


def _bars(run: RunLog, labels: dict[int, str]) -> list[report_figures.Bar]:
    """A bar per stretch of consecutive ticks in which a leaf was ticked and returned one status: it ends when
    the status changes or the leaf is no longer ticked (a leaf that returned SUCCESS and then waits, not ticked,
    for its parent to reset it is not painted on until the reset)."""
    ticks = run.ticks
    if not ticks:
        return []
    if not any(node.ticked for record in ticks for node in record.nodes):
        return _bars_by_changes(run, labels)  # a log that does not say which nodes were ticked
    period_ns = (ticks[-1].stamp_ns - ticks[0].stamp_ns) // max(len(ticks) - 1, 1) if len(ticks) > 1 else 10**7
    open_bar: dict[int, tuple[int, str, int]] = {}  # uid -> (start_ns, status, index of the last tick)
    bars: list[report_figures.Bar] = []

    def close(uid: int, end_ns: int) -> None:
        start, status, _ = open_bar.pop(uid)
        bars.append(report_figures.Bar(labels[uid], start * 1e-9, (end_ns - start) * 1e-9, status))

    for index, record in enumerate(ticks):
        end_ns = ticks[index + 1].stamp_ns if index + 1 < len(ticks) else record.stamp_ns + period_ns
        for node in record.nodes:
            if node.uid not in labels or not node.ticked:
                continue
            current = open_bar.get(node.uid)
            if current is not None and (current[1] != node.status or current[2] != index - 1):
                close(node.uid, ticks[current[2] + 1].stamp_ns if current[2] + 1 < len(ticks) else end_ns)
                current = None
            if node.status not in report_figures.STATUS_COLOURS:
                continue
            start = current[0] if current is not None else record.stamp_ns
            open_bar[node.uid] = (start, node.status, index)
        for uid in [u for u, (_, _, last) in open_bar.items() if last < index]:  # not ticked this tick: it ended
            close(uid, record.stamp_ns)
    for uid in list(open_bar):
        last = open_bar[uid][2]
        close(uid, ticks[last + 1].stamp_ns if last + 1 < len(ticks) else ticks[-1].stamp_ns + period_ns)
    return bars


def _bars_by_changes(run: RunLog, labels: dict[int, str]) -> list[report_figures.Bar]:
    end_s = run.ticks[-1].stamp_ns * 1e-9
    open_bar: dict[int, tuple[float, str]] = {}
    bars: list[report_figures.Bar] = []
    for ch in replay.status_changes(run):
        if ch.uid not in labels:
            continue
        t = ch.stamp_ns * 1e-9
        if ch.uid in open_bar:
            start, status = open_bar.pop(ch.uid)
            bars.append(report_figures.Bar(labels[ch.uid], start, t - start, status))
        if ch.new in report_figures.STATUS_COLOURS:
            open_bar[ch.uid] = (t, ch.new)
    for uid, (start, status) in open_bar.items():
        bars.append(report_figures.Bar(labels[uid], start, end_s - start, status))
    return bars


def _fault_marks(run: RunLog) -> list[tuple[float, str]]:
    """(simulated time, short text) of every injected fault that fired, for the timeline."""
    marks = []
    for fault in run.faults:
        what = fault.get("fault")
        text = str(what.get("label") or what.get("kind") or what) if isinstance(what, dict) else str(what)
        marks.append((int(fault.get("stamp_ns", 0)) * 1e-9, text))
    return marks


def _fault_text(fault: JsonValue) -> str:
    """A fired fault as its label and effect (``frame_drop@Perceive#1: no frame``), else as recorded."""
    if not isinstance(fault, dict):
        return str(fault)
    details = fault.get("details")
    effect = details.get("effect") if isinstance(details, dict) else None
    label = fault.get("label") or fault.get("kind")
    return f"{label}: {effect}" if label and effect else str(label or fault)


def end_statuses(run: RunLog) -> dict[int, str]:
    """Every node's status at the end of the run: the last status it returned when ticked (the final reset
    to IDLE that follows the root's completion is not news; a node never ticked stays IDLE)."""
    out: dict[int, str] = {}
    for record in run.ticks:
        for node in record.nodes:
            if node.ticked and node.status != "IDLE":
                out[node.uid] = node.status
    return out


def _joint_series(run: RunLog) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], list[str]]:
    times, q, width = [], [], []
    names: list[str] = []
    for stamp_ns, m in run.joint_states():
        times.append(stamp_ns * 1e-9)
        q.append(m.get("position", []))
        width.append(m.get("gripper_width_m") if m.get("gripper_width_m") is not None else np.nan)
        names = list(m.get("name", names))
    n = max((len(row) for row in q), default=0)
    Q = np.array([row + [np.nan] * (n - len(row)) for row in q], dtype=np.float64).reshape(len(times), n)
    return np.array(times), Q, np.array(width, dtype=np.float64), names


def _timed(run: RunLog, topic: str) -> list[tuple[int, Message]]:
    return list(run.protobuf_messages(topic))


def _at(items: Sequence[tuple[int, _T]], stamp_ns: int) -> _T | None:
    """The item written at exactly ``stamp_ns`` (a capture's own detections), else None."""
    return next((value for t, value in items if t == stamp_ns), None)


def _last_before(items: Sequence[tuple[int, _T]], stamp_ns: int) -> _T | None:
    found: _T | None = None
    for t, value in items:
        if t > stamp_ns:
            break
        found = value
    return found


def _camera_poses(run: RunLog) -> list[tuple[int, NDArray[np.float64]]]:
    out = []
    for t, msg in _timed(run, topics.TF):
        for tf in msg.transforms:
            if tf.child_frame_id in _CAMERA_FRAMES:
                q, p = tf.rotation, tf.translation
                R = _quat_to_R(q.x, q.y, q.z, q.w)
                out.append((t, make_T(R, [p.x, p.y, p.z])))
    return out


def _quat_to_R(x: float, y: float, z: float, w: float) -> NDArray[np.float64]:
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _boxes(update: Message) -> list[tuple[NDArray[np.float64], tuple[float, float, float], str]]:
    boxes = []
    for entity in getattr(update, "entities", []):
        label = next((kv.value for kv in entity.metadata if kv.key == "label"), entity.id)
        for cube in entity.cubes:
            q, p = cube.pose.orientation, cube.pose.position
            T = make_T(_quat_to_R(q.x, q.y, q.z, q.w), [p.x, p.y, p.z])
            boxes.append((as_matrix(T), (cube.size.x, cube.size.y, cube.size.z), label))
    return boxes


def _frames(run: RunLog) -> list[tuple[str, bytes]]:
    images = [im for im in run.images() if im.kind == "color"]
    if len(images) > _MAX_FRAMES:  # the first ones (Perceive's), then evenly spaced, and the last
        keep = sorted(set(np.linspace(0, len(images) - 1, _MAX_FRAMES).round().astype(int).tolist()))
        images = [images[i] for i in keep]
    if not images:
        return []
    detections = _timed(run, topics.DETECTIONS)
    calibrations = _timed(run, topics.CALIBRATION)
    poses = _camera_poses(run)
    out = []
    for im in images:
        update = _at(detections, im.stamp_ns)  # boxes only on the capture they were detected in
        calib = _last_before(calibrations, im.stamp_ns) or (calibrations[0][1] if calibrations else None)
        K = np.array(calib.K, dtype=np.float64).reshape(3, 3) if calib is not None and len(calib.K) == 9 else None
        T_base_camera = _last_before(poses, im.stamp_ns)
        T_camera_base = np.linalg.inv(T_base_camera) if T_base_camera is not None else None
        caption = f"t = {im.stamp_ns * 1e-9:.2f} s"
        rgb = np.asarray(im.pixels, dtype=np.uint8)  # a colour image is uint8 already: no copy
        png = report_figures.frame_with_boxes(rgb, K, T_camera_base, _boxes(update) if update else [], caption)
        out.append((caption, png))
    return out


# -- the page ----------------------------------------------------------------------------------------------


def _tree_html(node: AnnotatedNode, counts: dict[int, tuple[int, int, int]]) -> str:
    attempts, failures, retries = counts.get(int(node["uid"]), (0, 0, 0))
    extra = []
    if attempts:
        extra.append(f"{attempts} attempt{'s' if attempts != 1 else ''}")
    if failures:
        extra.append(f"{failures} failure{'s' if failures != 1 else ''}")
    if retries:
        extra.append(f"{retries} retr{'ies' if retries != 1 else 'y'}")
    reason = f' <span class="reason">{_esc(node["failure_reason"])}</span>' if node.get("failure_reason") else ""
    head = (f'<span class="node">{_esc(node.get("name"))}</span> <span class="type">{_esc(node.get("type"))}'
            f"</span> {_badge(node['status'])}{reason}"
            + (f' <span class="counts">{_esc(", ".join(extra))}</span>' if extra else ""))
    children = "".join(_tree_html(c, counts) for c in node.get("children", []))
    return f"<li>{head}" + (f"<ul>{children}</ul>" if children else "") + "</li>"


def _with_end_statuses(node: AnnotatedNode, statuses: dict[int, str]) -> None:
    node["status"] = statuses.get(int(node["uid"]), node["status"])
    for child in node.get("children", []):
        _with_end_statuses(child, statuses)


_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:24px auto;max-width:1100px;color:#222}
h1{margin-bottom:4px} h2{border-bottom:1px solid #ddd;padding-bottom:4px;margin-top:32px}
table{border-collapse:collapse} td,th{padding:3px 10px;text-align:left;border-bottom:1px solid #eee;vertical-align:top}
.st{padding:1px 6px;border-radius:4px;color:#fff;font-size:12px;font-weight:600}
.st-SUCCESS{background:#3aa657}.st-FAILURE{background:#d64545}.st-RUNNING{background:#4a7fd6}
.st-IDLE{background:#999}.st-SKIPPED{background:#bbb}
.tree ul{list-style:none;padding-left:22px;border-left:1px dashed #bbb;margin:2px 0}
.tree>ul{border-left:none;padding-left:0}.tree li{margin:3px 0}
.type{color:#777;font-size:12px}.counts{color:#a15c00;font-size:12px}.reason{color:#d64545;font-weight:600}
img{max-width:100%;border:1px solid #ddd;margin:6px 0}
.frames{display:grid;grid-template-columns:repeat(auto-fill,minmax(320px,1fr));gap:10px}
.ok{color:#3aa657;font-weight:700}.bad{color:#d64545;font-weight:700}
"""


def build_report(run: RunLog, html_path: Path, png_dir: Path | None = None, repeated: Collection[int] = ()
                 ) -> Report:
    """Write the report page (and the PNG figures to ``png_dir``); returns what was written. ``repeated``: the
    numbers of the attempts that repeat a failed earlier one (``bt_grasp.behaviours.attempts.repeats``)."""
    report = Report(Path(html_path))
    s = replay.summary(run)
    rows, labels = _leaf_rows(run)
    every_failure = replay.failures(run)
    # failures to explain: not the conditions false by design (control flow: FailureIs in a Fallback, ForceFailure)
    failures = [f for f in every_failure if f.kind != replay.FailureKind.BY_DESIGN]
    by_design = len(every_failure) - len(failures)
    bars = _bars(run, labels)
    shown = {bar.row for bar in bars}
    rows = [row for row in rows if row in shown]  # leaves that never ran would be empty rows
    fault_marks = _fault_marks(run)
    report.figures["gantt"] = report_figures.gantt(
        rows, bars, [(f.stamp_ns * 1e-9, labels[f.uid]) for f in failures if f.uid in labels], fault_marks)
    fail_s = [f.stamp_ns * 1e-9 for f in failures]
    t, Q, width, names = _joint_series(run)
    if t.size:
        report.figures["joints"] = report_figures.series(t, Q, names, "Joint angles", "rad", fail_s, fault_marks)
        if np.isfinite(width).any():
            report.figures["gripper"] = report_figures.series(t, width, ["opening"], "Gripper opening", "m", fail_s,
                                                              fault_marks)
    frames = _frames(run)
    for i, (_, png) in enumerate(frames):
        report.figures[f"frame_{i:02d}"] = png

    result = run.result or {}
    success = result.get("success")
    verdict = ('<span class="ok">SUCCESS</span>' if success else '<span class="bad">FAILURE</span>'
               if success is not None else f"<span>interrupted (Ctrl-C) at tick {_esc(result.get('ticks'))}</span>"
               if result.get("interrupted") else "<span>unfinished (no result recorded)</span>")
    summary_rows = [
        ("outcome", verdict),
        ("reason", _esc(result.get("reason"))), ("failed leaf", _esc(result.get("failed_leaf"))),
        ("tree", _esc(s["tree"])), ("scene", _esc(s["scene"])), ("seed", _esc(s["seed"])),
        ("ticks", _esc(s["ticks"])), ("simulated time", f"{s['sim_duration_s']:.2f} s"),
        ("wall time", _esc(f"{result['wall_time_s']:.2f} s" if result.get("wall_time_s") is not None else "")),
        ("retries", _esc(s["retries"])),
        ("fault plan", _esc(s["fault_plan"] or run.metadata.get("inject", "") or "none")),
        ("log", _esc(run.path.name) + (" (truncated: the run did not finish)" if run.truncated else "")),
    ]
    parts = [f"<h1>Run report: {_esc(Path(s['tree']).name or run.path.name)}</h1>",
             f"<p>{verdict} &middot; {_esc(run.path.name)} &middot; bt_grasp log format "
             f"{_esc(run.metadata.get('log_format', '1'))}</p>",
             "<h2>Summary</h2><table>" + "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in summary_rows)
             + "</table>"]
    parts.append("<h2>Attempts (grasps and placements) and what each ruled out</h2>"
                 + attempts_html(attempt_rows(run.attempts, repeated)))
    parts.append("<h2>Failures and recovery</h2>")
    if failures:
        items = []
        for f in failures:
            recovery = ", ".join(f"{c.path or c.name} {c.new} (t={c.stamp_ns * 1e-9:.2f} s)"
                                 for c in f.recovery) or "nothing"
            decided = "decided the outcome" if f.decided else "recovered"
            items.append(f"<tr><td>{decided}</td><td>{f.stamp_ns * 1e-9:.2f} s</td><td>tick {f.tick}</td>"
                         f"<td>{_esc(f.path or f.name)}</td>"
                         f'<td class="reason">{_esc(f.reason)}</td><td>{_esc(" > ".join(f.propagated_to))}</td>'
                         f"<td>{_esc(recovery)}</td></tr>")
        parts.append("<table><tr><th></th><th>time</th><th>tick</th><th>leaf</th><th>reason</th>"
                     "<th>propagated to</th><th>what ran next (recovery)</th></tr>" + "".join(items) + "</table>")
    else:
        parts.append("<p>No leaf failed.</p>")
    if by_design:
        parts.append(f'<p class="type">Not listed: {by_design} conditions false by design (a FailureIs asked by '
                     "a Fallback, ForceFailure): control flow, not failures.</p>")
    if run.faults:
        parts.append("<h3>Injected faults</h3><table>" + "".join(
            f"<tr><td>{f['stamp_ns'] * 1e-9:.2f} s</td><td>tick {_esc(f.get('tick'))}</td>"
            f"<td>{_esc(_fault_text(f.get('fault')))}</td></tr>" for f in run.faults) + "</table>")
    if run.interventions:
        parts.append(interventions_html(run.interventions))
    last_tick = run.ticks[-1].tick if run.ticks else None
    if last_tick is not None:
        tree = replay.tree_at(run, last_tick)
        _with_end_statuses(tree, end_statuses(run))
        parts.append(f"<h2>The tree at the end (tick {last_tick}): each node's last status</h2>"
                     f'<div class="tree"><ul>{_tree_html(tree, replay.attempts(run))}</ul></div>')
    parts.append("<h2>Leaf statuses over time</h2>" + _img(report.figures["gantt"], "Gantt of leaf statuses"))
    if "joints" in report.figures:
        parts.append("<h2>Arm</h2>" + _img(report.figures["joints"], "joint angles"))
    if "gripper" in report.figures:
        parts.append(_img(report.figures["gripper"], "gripper opening"))
    parts.append("<h2>Camera frames with detections</h2>")
    if frames:
        parts.append('<div class="frames">' + "".join(_img(png, cap) for cap, png in frames) + "</div>")
    else:
        parts.append("<p>No camera frame in this log.</p>")
    page = ("<!doctype html><html><head><meta charset=\"utf-8\"><title>bt_grasp run report</title>"
            f"<style>{_CSS}</style></head><body>" + "\n".join(parts) + "</body></html>\n")
    write_output_file(report.html_path, page, "--report", example="report.html")
    if png_dir is not None:
        make_output_folder(png_dir, "--report-dir")
        for name, png in report.figures.items():
            report.pngs.append(write_output_file(png_dir / f"{name}.png", png, "--report-dir"))
    return report
