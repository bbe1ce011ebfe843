"""Rich renderables for `bt-grasp replay`: built here, printed by the command (which owns the console).

Names and feedback come from files, so they are always wrapped in ``Text`` (never parsed as markup).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence

from rich.console import Group, RenderableType
from rich.table import Table
from rich.text import Text
from rich.tree import Tree

from bt_grasp.files.json_types import JsonValue
from bt_grasp.recording.messages import LoggedJointState
from bt_grasp.recording.replay import FailureKind, FailureReport, FaultMark, StatusChange
from bt_grasp.recording.replay_shapes import AnnotatedNode, LeafState, ReplaySummary
from bt_grasp.tree.values import display

STATUS_STYLES = {"SUCCESS": "green", "FAILURE": "bold red", "RUNNING": "yellow", "IDLE": "dim",
                 "SKIPPED": "blue"}
_SHORT = {"SUCCESS": "OK", "FAILURE": "FAIL", "RUNNING": "RUN", "IDLE": "idle", "SKIPPED": "skip"}


def status_text(status: str, short: bool = False) -> Text:
    return Text(_SHORT.get(status, status) if short else status, style=STATUS_STYLES.get(status, ""))


def _seconds(stamp_ns: int) -> str:
    return f"{stamp_ns * 1e-9:.3f}s"


def _value(value: JsonValue, limit: int = 80) -> str:
    # numbers and bools as BT.CPP prints them (a real with six decimals); the log itself keeps them typed
    text = display(value) if isinstance(value, str | int | float) else json.dumps(value, separators=(",", ":"))
    return text if len(text) <= limit else text[: limit - 1] + "…"


def summary_table(s: ReplaySummary) -> Table:
    table = Table(show_header=False, box=None, pad_edge=False)
    table.add_column(style="bold")
    table.add_column()
    outcome: Text
    if s.get("interrupted"):
        outcome = Text(f"INTERRUPTED (Ctrl-C) at tick {(s['result'] or {}).get('ticks', '?')}: not judged",
                       style="bold yellow")
    elif s["success"] is None:
        outcome = Text("no result recorded", style="yellow")
    else:
        ok = bool(s["success"])
        outcome = Text("SUCCESS" if ok else "FAILURE", style="green" if ok else "bold red")
    meta = s.get("metadata") or {}
    on_cell = meta.get("ran_on") in ("twin", "robot")  # a real cell's run (or a twin's): wall-clock time
    rows: list[tuple[str, str | Text]] = [
        ("log", s["file"]),
        ("tree", s["tree"] or "-"),
        ("cell", f"{meta.get('cell_file', '-')} (the {meta['ran_on']} at {meta.get('arm_address', '?')}, "
                 "wall clock)") if on_cell else ("scene", s["scene"] or "-"),
        ("seed", "-" if s["seed"] is None else str(s["seed"])),
        ("fault plan", s["fault_plan"] or "-"),
        ("result", outcome),
        ("reason", str(s["reason"]) if s["reason"] else "-"),
        ("failed leaf", str(s.get("failed_path") or s["failed_leaf"]) if s["failed_leaf"] else "-"),
        ("ticks", f"{s['ticks']} (ticks {s['first_tick']}..{s['last_tick']})" if s["ticks"] else "0"),
        ("wall duration" if on_cell else "sim duration", f"{s['sim_duration_s']:.3f} s"),
        ("retries", str(s["retries"])),
    ]
    for name, count in s["retries_per_leaf"].items():
        rows.append(("  retries of", f"{name}: {count}"))
    for name, count in s["failures_per_leaf"].items():
        rows.append(("  failures of", f"{name}: {count}"))
    by_design = s.get("false_by_design_per_leaf") or {}
    if by_design:  # counted, not listed: a condition asked by a Fallback, a ForceFailure (--failures lists them)
        rows.append(("  false by design", f"{sum(by_design.values())} (conditions and decorators; --failures "
                                          "lists them)"))
    if s["faults"]:
        rows.append(("faults fired", str(len(s["faults"]))))
    if s.get("interventions"):
        rows.append(("interventions", f"{len(s['interventions'])} (listed below)"))
    truncated = Text(f"yes: file not finished, {s['ticks_recovered']} ticks recovered", style="yellow") \
        if s["truncated"] else Text("no")
    rows.append(("truncated", truncated))
    for key, value in rows:
        table.add_row(key, value if isinstance(value, Text) else Text(value))
    return table


FAULT_STYLE = "bold magenta"


def fault_text(mark: FaultMark) -> Text:
    """``FAULT frame_drop@Perceive#1 (frame_drop) on pick/Perceive: no frame`` (text from the log: never markup)."""
    line = Text("FAULT ", style=FAULT_STYLE)
    line.append(mark.text(), style="magenta")
    return line


def timeline_table(rows: Sequence[tuple[int, int, list[StatusChange]]], max_rows: int,
                   faults: Sequence[FaultMark] = ()) -> RenderableType:
    """The ticks in which some node changed status, with every injected fault marked on its own row at the tick
    it fired (after that tick's status changes, if any)."""
    table = Table(title="status changes" + (" and injected faults" if faults else ""), title_justify="left",
                  box=None, pad_edge=False)
    table.add_column("tick", justify="right", style="cyan")
    table.add_column("sim time", justify="right")
    table.add_column("changes")
    entries: list[tuple[int, int, int, Text]] = []
    for mark in faults:
        entries.append((mark.tick, 1, mark.stamp_ns, fault_text(mark)))
    for tick, stamp, changes in rows:
        line = Text()
        for i, ch in enumerate(changes):
            if i:
                line.append("  ")
            line.append(ch.path or ch.name)  # the node's one name (tree show, the report, Foxglove)
            line.append(" ")
            line.append_text(status_text(ch.new, short=True))
        entries.append((tick, 0, stamp, line))
    entries.sort(key=lambda e: (e[0], e[1]))
    for tick, _order, stamp, line in entries[:max_rows]:
        table.add_row(str(tick) if tick >= 0 else "?", _seconds(stamp), line)
    if len(entries) > max_rows:
        hidden = entries[max_rows:]
        faults_hidden = sum(1 for e in hidden if e[1] == 1)
        more = Text(f"… {len(hidden) - faults_hidden} more ticks with changes"
                    + (f" and {faults_hidden} more faults" if faults_hidden else "")
                    + " (--max-rows to show more)", style="dim")
        return Group(table, more)
    return table


def _node_label(node: AnnotatedNode) -> Text:
    label = Text()
    name, type_name = node["name"], node["type"]
    label.append(name, style="bold" if node.get("ticked") else "")
    if type_name and type_name != name:
        label.append(f" ({type_name})", style="dim")
    label.append(" ")
    label.append_text(status_text(node["status"]))
    if node.get("ticked"):
        label.append(" ●", style="cyan")
    if node.get("feedback"):
        label.append(f"  {node['feedback']}", style="italic")
    if node.get("failure_reason"):
        label.append(f"  reason: {node['failure_reason']}", style="red")
    return label


def tree_render(tree: AnnotatedNode, title: str) -> Tree:
    root = Tree(Text(title, style="bold"))
    stack: list[tuple[Tree, AnnotatedNode]] = [(root, tree)]
    while stack:
        parent, node = stack.pop()
        branch = parent.add(_node_label(node))
        stack.extend((branch, child) for child in reversed(node.get("children", [])))
    return root


def mapping_table(title: str, values: Mapping[str, JsonValue], sort: bool = True) -> Table:
    table = Table(title=title, title_justify="left", box=None, pad_edge=False, show_header=False)
    table.add_column(style="bold")
    table.add_column()
    for key in sorted(values) if sort else values:
        table.add_row(Text(key), Text(_value(values[key])))
    if not values:
        table.add_row(Text("(empty)", style="dim"), Text(""))
    return table


def robot_table(robot: LoggedJointState | None) -> Table:
    if robot is None:
        return mapping_table("arm", {})
    q = robot.get("position", [])
    rows: dict[str, JsonValue] = {
        "q (rad)": " ".join(f"{v:+.4f}" for v in q),
        "q (deg)": " ".join(f"{math.degrees(v):+.2f}" for v in q),
        "qd (rad/s)": " ".join(f"{v:+.4f}" for v in robot.get("velocity", [])),
    }
    width = robot.get("gripper_width_m")
    rows["gripper width (m)"] = "-" if width is None else f"{width:.4f}"
    if "tcp_xyz_m" in robot:
        rows["tcp xyz (m)"] = " ".join(f"{v:+.4f}" for v in robot["tcp_xyz_m"])
        rows["tcp quat xyzw"] = " ".join(f"{v:+.4f}" for v in robot["tcp_quat_xyzw"])
    return mapping_table("arm", rows, sort=False)


def failures_table(reports: Sequence[FailureReport]) -> RenderableType:
    """The failures that mattered, each with where it propagated and what ran next (the one that decided the
    outcome marked), then, apart and dimmed, the conditions that were false by design (a ``FailureIs`` asked
    by a Fallback, ``ForceFailure``)."""
    if not reports:
        return Text("no failures recorded", style="green")
    real = [f for f in reports if f.kind != FailureKind.BY_DESIGN]
    by_design = [f for f in reports if f.kind == FailureKind.BY_DESIGN]
    parts: list[RenderableType] = [Text("failures", style="italic")]
    if not real:
        parts.append(Text("no leaf failed (apart from conditions false by design)", style="green"))
    for f in real:
        head = Text("  ")
        head.append("decided the outcome" if f.decided else "recovered", style="bold red" if f.decided else "yellow")
        head.append(f"  tick {f.tick}  {_seconds(f.stamp_ns)}  ")
        head.append(f.path or f.name, style="bold")
        head.append("  ")
        head.append(f.reason or "-", style="red")
        parts.append(head)
        parts.append(Text(f"      propagated to: {' > '.join(f.propagated_to) or '-'}"))
        nxt = Text("      then: ")
        for i, ch in enumerate(f.recovery):
            if i:
                nxt.append(", ")
            nxt.append(f"{ch.path or ch.name} (tick {ch.tick}) ")
            nxt.append_text(status_text(ch.new, short=True))
        if not f.recovery:
            nxt.append("nothing (the run ended)", style="dim")
        parts.append(nxt)
    if by_design:
        table = Table(title=f"false by design: {len(by_design)} (control flow, not faults)", title_justify="left",
                      box=None, pad_edge=False, style="dim")
        for column in ("tick", "sim time"):
            table.add_column(column, no_wrap=True, style="dim")
        table.add_column("leaf", overflow="fold", style="dim")  # a path is never cut short
        table.add_column("reason", style="dim")
        for f in by_design:
            table.add_row(str(f.tick), _seconds(f.stamp_ns), Text(f.path or f.name), Text(f.reason or "-"))
        parts += [Text(""), table]
    return Group(*parts)


def leaf_table(name: str, history: Sequence[LeafState], max_rows: int) -> RenderableType:
    table = Table(title=Text(f"history of {name}"), title_justify="left", box=None, pad_edge=False)
    for column in ("tick", "sim time", "status", "ticked", "feedback", "reason"):
        table.add_column(column)
    for row in history[:max_rows]:
        table.add_row(Text(str(row["tick"]), style="cyan"), Text(_seconds(row["stamp_ns"])),
                      status_text(row["status"]), Text("yes" if row["ticked"] else ""),
                      Text(row["feedback"] or ""), Text(row["failure_reason"] or "", style="red"))
    if len(history) > max_rows:
        return Group(table, Text(f"… {len(history) - max_rows} more rows (--max-rows)", style="dim"))
    return table
