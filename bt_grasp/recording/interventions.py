"""An interactive run's interventions (``/control/interventions``) as replay and the run report show them."""

from __future__ import annotations

import html
import json
from collections.abc import Sequence

from rich.table import Table
from rich.text import Text

from bt_grasp.recording.messages import LoggedIntervention


def _command(record: LoggedIntervention) -> str:
    command = record.get("command")
    if not isinstance(command, dict):
        return ""
    fields = {k: v for k, v in command.items() if k != "kind"}
    return json.dumps(fields, separators=(", ", ": "), default=str) if fields else ""


def rows(records: Sequence[LoggedIntervention]) -> list[tuple[str, str, str, str, str, str]]:
    """(time s, tick, source, kind, command fields, effect) per intervention, as text."""
    return [(f"{int(r.get('stamp_ns', 0)) * 1e-9:.3f}", str(r.get("tick", "")), str(r.get("source", "")),
             str(r.get("kind", "")), _command(r), str(r.get("effect", ""))) for r in records]


def interventions_table(records: Sequence[LoggedIntervention]) -> Table:
    """What ``bt-grasp replay LOG`` lists after the timeline when the run had interventions."""
    table = Table(title=f"interventions ({len(records)}): applied after their tick, re-applied by --resim")
    for name in ("time s", "tick", "by", "what", "command", "effect"):
        table.add_column(name)
    for row in rows(records):
        table.add_row(*(Text(cell) for cell in row))
    return table


def interventions_html(records: Sequence[LoggedIntervention]) -> str:
    """The run report's section (empty when the run had none)."""
    if not records:
        return ""
    body = "".join("<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>" for row in rows(records))
    return ('<h3 id="interventions">Operator interventions</h3><p>Applied at the tick boundary after the tick shown; '
            "<code>bt-grasp replay LOG --resim</code> applies them again there.</p><table><tr><th>time (s)</th>"
            "<th>tick</th><th>by</th><th>what</th><th>command</th><th>effect</th></tr>" + body + "</table>")
