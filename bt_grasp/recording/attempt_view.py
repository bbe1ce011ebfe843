"""The run's grasp and placement attempts (``/bt/attempts``, log format 4) as rows, a terminal table and HTML:
what ``replay --attempts`` and the run report show.

Each row: the attempt's number, the tick it was made and ended, the leaf, the object as perceived, the grasp
family, where (the tool for a grasp, the object's rest pose for a placement), how it ended, and what earlier
attempts ruled out before it was chosen (each exclusion with the attempt that caused it and the rule). A
notice that a leaf had nothing left to try (outcome SKIPPED) is a row too. Whether an attempt repeats an earlier
one is decided by ``bt_grasp.behaviours.attempts.repeats`` (the caller passes the numbers of the ones that do).
"""

from __future__ import annotations

import html
from collections.abc import Collection, Sequence
from typing import TypedDict

from rich.table import Table

from bt_grasp.files.json_types import JsonObject, JsonValue
from bt_grasp.files.terminal_text import shown


class AttemptRow(TypedDict):
    index: int
    tick: int
    end_tick: int
    kind: str
    leaf: str
    object: str
    family: str
    where: str
    outcome: str
    excluded: list[str]
    repeats: bool


def _num(value: JsonValue) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else 0.0


def _numbers(value: JsonValue) -> list[float]:
    return [_num(v) for v in value] if isinstance(value, list) else []


def _object_text(value: JsonValue) -> str:
    if not isinstance(value, dict):
        return "-"
    name = str(value.get("class_name") or value.get("label") or "object")
    c = _numbers(value.get("centroid_m"))
    return f"{name} at ({c[0]:.3f}, {c[1]:.3f})" if len(c) >= 2 else name


def _where(msg: JsonObject) -> str:
    if msg.get("kind") == "place":
        p = _numbers(msg.get("place_pose"))
        blocked = msg.get("blocked")
        n = len(blocked) if isinstance(blocked, list) else 0
        at = f"object at {p[0]:.3f};{p[1]:.3f};{p[2]:.3f};{p[3]:.0f}" if len(p) == 4 else "-"
        return at + (f", {n} orientation(s) blocked" if n else "")
    t = _numbers(msg.get("tcp_xyz_m"))
    return (f"tool {t[0]:.3f};{t[1]:.3f};{t[2]:.3f} {msg.get('approach', '')}".rstrip() if len(t) == 3 else "-")


def _exclusions(msg: JsonObject) -> list[str]:
    out = []
    items = msg.get("excluded")
    for e in items if isinstance(items, list) else []:
        if isinstance(e, dict):
            by = int(_num(e.get("by")))
            out.append(f"{e.get('what', '')}: {e.get('detail', '')}" + (f" (attempt #{by}, {e.get('rule', '')})"
                                                                          if by >= 0 else ""))
    return out


def attempt_rows(attempts: Sequence[JsonObject], repeated: Collection[int] = ()) -> list[AttemptRow]:
    """One row per ``/bt/attempts`` message, in order; ``repeated``: the numbers of attempts that repeat a failed
    earlier one."""
    rows: list[AttemptRow] = []
    for msg in attempts:
        index = int(_num(msg.get("index")))
        reason = str(msg.get("reason") or "")
        rows.append({
            "index": index, "tick": int(_num(msg.get("tick"))), "end_tick": int(_num(msg.get("end_tick"))),
            "kind": str(msg.get("kind", "")), "leaf": str(msg.get("leaf", "")),
            "object": _object_text(msg.get("object")), "family": str(msg.get("family", "")), "where": _where(msg),
            "outcome": str(msg.get("outcome", "")) + (f" {reason}" if reason else ""),
            "excluded": _exclusions(msg), "repeats": index in repeated,
        })
    return rows


def attempts_table(rows: Sequence[AttemptRow], title: str = "attempts (grasps and placements)") -> Table:
    table = Table(title=title)
    for column in ("#", "tick", "kind", "object", "family", "where", "ended", "ruled out before it"):
        table.add_column(column, overflow="fold")
    for row in rows:
        mark = " REPEAT" if row["repeats"] else ""
        table.add_row(str(row["index"]), f"{row['tick']}-{row['end_tick']}", row["kind"], shown(row["object"]),
                      row["family"], shown(row["where"]), shown(row["outcome"]) + mark,
                      shown("\n".join(row["excluded"])) or "-")
    return table


def attempts_html(rows: Sequence[AttemptRow]) -> str:
    """The rows as an HTML table (the run report's "Attempts" section)."""
    if not rows:
        return "<p>No grasp or placement attempt was recorded (a log written before /bt/attempts has none).</p>"
    head = "".join(f"<th>{h}</th>" for h in ("#", "ticks", "kind", "leaf", "object", "family", "where", "ended",
                                               "ruled out before it"))
    body = []
    for row in rows:
        ended = html.escape(row["outcome"]) + (" <b>REPEAT</b>" if row["repeats"] else "")
        cells = [str(row["index"]), f"{row['tick']}-{row['end_tick']}", row["kind"], row["leaf"], row["object"],
                 row["family"], row["where"]]
        excluded = "<br>".join(html.escape(e) for e in row["excluded"]) or "-"
        body.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + f"<td>{ended}</td>"
                    f"<td>{excluded}</td></tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"
