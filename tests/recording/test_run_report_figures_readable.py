"""The run report's figures as drawn (issue 43, finding 9): each test looks at the rendered picture.

A hand-written log (the real writer and reader, no simulator) of a 20 s run at 100 ticks a second: its tree is
``root`` (Sequence) over ``Load`` (done within tick 1, as LoadCalibration or a Script is), ``Move`` (ticks 2-1999)
and ``Check`` (done within the last tick). Joints 3 and 4 move together the whole run (as the UR5's wrist joints
do at home: both at -1.57 rad); a fault fires at tick 1000.

- A leaf that finishes within a tick has a mark on its Gantt row (one tick of 20 s was a bar a third of a pixel
  wide: the row looked empty).
- The joint plot shows every curve (joint 3 was drawn under joint 4) and the fault's line (it had none).
- No legend covers a label, and no text runs past the picture's edge.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bt_grasp.recording import report, report_figures
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder
from tests.figure_checks import count_colour, legend_overlaps, pixels, texts_cut

TICK_NS = 10_000_000
TICKS = 2000
FAULT_TICK = 1000
LEAVES = {2: "Load", 3: "Move", 4: "Check"}
STRUCTURE = {"uid": 1, "type": "Sequence", "name": "root", "path": "root", "kind": "Control", "attributes": {},
             "children": [{"uid": uid, "type": name, "name": name, "path": f"{name}::{uid}", "kind": "Action",
                           "attributes": {}, "children": []} for uid, name in LEAVES.items()]}


def _node(uid: int, status: str, ticked: bool) -> dict[str, Any]:
    name = "root" if uid == 1 else LEAVES[uid]
    path = "root" if uid == 1 else f"{name}::{uid}"
    return {"uid": uid, "path": path, "name": name, "type": "Sequence" if uid == 1 else name,
            "kind": "Control" if uid == 1 else "Action", "status": status, "ticked": ticked, "feedback": "",
            "failure_reason": None}


def _statuses(tick: int) -> list[dict[str, Any]]:
    if tick == 1:  # Load done at once; Move starts in the same tick
        return [_node(1, "RUNNING", True), _node(2, "SUCCESS", True), _node(3, "RUNNING", True),
                _node(4, "IDLE", False)]
    if tick < TICKS:
        return [_node(1, "RUNNING", True), _node(2, "SUCCESS", False), _node(3, "RUNNING", True),
                _node(4, "IDLE", False)]
    return [_node(1, "SUCCESS", True), _node(2, "IDLE", False), _node(3, "SUCCESS", True), _node(4, "SUCCESS", True)]


def _joints(tick: int) -> list[float]:
    s = tick / TICKS
    wrist = -1.57 + 0.3 * np.sin(2 * np.pi * s)  # joints 3 and 4 together, all run long
    return [0.2 * s, -1.9 + 0.4 * s, 1.9 - 0.5 * s, wrist, wrist, 0.6 * s]


@pytest.fixture(scope="module")
def log_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("log") / "run.mcap"
    with RunRecorder(path, metadata={"seed": "0", "tree_file": "t.xml"}, handle_signals=False,
                     time_origin_ns=1_700_000_000 * 10**9) as rec:
        rec.write_tree_structure(0, STRUCTURE)
        for tick in range(1, TICKS + 1):
            stamp = (tick - 1) * TICK_NS
            if tick == FAULT_TICK:
                rec.write_fault(stamp, tick, {"kind": "gripper_slip", "label": "gripper_slip@Move#1"})
            rec.write_tick(tick, stamp, _statuses(tick), {},
                           {"q_rad": _joints(tick), "qd_rad_s": [0.0] * 6, "gripper_width_m": 0.08})
        rec.write_result((TICKS - 1) * TICK_NS, {"success": True, "reason": None, "failed_leaf": None})
    return path


@pytest.fixture(scope="module")
def drawn(log_path: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The run report's figures, caught where each is turned into PNG bytes, by the function that drew it."""
    caught: dict[str, Any] = {}
    real = report_figures._png
    patch = pytest.MonkeyPatch()

    def spy(name: str) -> Any:
        draw = getattr(report_figures, name)

        def wrapped(*args: Any, **kwargs: Any) -> bytes:
            def keep(fig: Any) -> bytes:
                caught.setdefault(f"{name}:{args[3] if name == 'series' else ''}", fig)
                return real(fig)

            patch.setattr(report_figures, "_png", keep)
            try:
                return bytes(draw(*args, **kwargs))
            finally:
                patch.setattr(report_figures, "_png", real)

        return wrapped

    for name in ("gantt", "series"):
        patch.setattr(report_figures, name, spy(name))
    try:
        report.build_report(open_log(log_path), tmp_path_factory.mktemp("report") / "r.html")
    finally:
        patch.undo()
    return caught


def _row_pixels(fig: Any, row: int, colour: str) -> int:
    """Pixels of ``colour`` in Gantt row ``row``'s band, inside the axes."""
    ax = fig.axes[0]
    image = pixels(fig)
    height = image.shape[0]
    _, y = ax.transData.transform((0.0, row))
    x0, x1 = int(ax.bbox.x0), int(ax.bbox.x1)
    band = image[int(height - y) - 3: int(height - y) + 4, x0:x1]
    return count_colour(band, colour)


def test_a_leaf_that_finishes_within_a_tick_has_a_mark_on_its_row(drawn: dict[str, Any]) -> None:
    fig = drawn["gantt:"]
    rows = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert rows == ["Load::2", "Move::3", "Check::4"], rows
    success = report_figures.STATUS_COLOURS["SUCCESS"]
    for row in (0, 2):  # Load and Check: SUCCESS within one tick of a 20 s run
        assert _row_pixels(fig, row, success) >= 3 * 7, f"{rows[row]}'s row looks empty"
    assert legend_overlaps(fig) == [] and texts_cut(fig) == []


def test_the_joint_plot_shows_every_curve_and_the_fault_line(drawn: dict[str, Any]) -> None:
    fig = drawn["series:Joint angles"]
    ax = fig.axes[0]
    image = pixels(fig)
    height = image.shape[0]
    inside = image[int(height - ax.bbox.y1): int(height - ax.bbox.y0), int(ax.bbox.x0): int(ax.bbox.x1)]
    curves = [line for line in ax.lines if np.asarray(line.get_xdata()).size > 2]  # not the vertical lines
    colours = {line.get_label(): line.get_color() for line in curves}
    assert len(colours) >= 6, colours
    for label, colour in colours.items():
        assert count_colour(inside, colour) > 50, f"the curve {label} ({colour}) cannot be seen"
    assert count_colour(inside, report_figures.FAULT_COLOUR) > 20, "no line where the fault fired"
    assert legend_overlaps(fig) == [] and texts_cut(fig) == []
