"""The run report's figures (matplotlib, drawn off-screen): leaf-status Gantt, joints, gripper opening, and
camera frames with the detections projected into them. Each function returns PNG bytes."""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bt_grasp.recording.projection import BOX_EDGES, box_corners_px

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure

STATUS_COLOURS = {"RUNNING": "#4a7fd6", "SUCCESS": "#3aa657", "FAILURE": "#d64545", "SKIPPED": "#b0b0b0"}
FAULT_COLOUR = "#e07b00"
#: a Gantt bar is drawn at least this share of the run long (0.5 %: 4 pixels of the 10-inch figure's axis)
MIN_BAR_FRACTION = 0.005
#: the joint plot's curves, drawn in order: each thinner than the one before and broken by gaps, so a curve that
#: lies on an earlier one (the UR5's wrist joints at home are both -1.57 rad) leaves the earlier one in sight
CURVE_WIDTHS = (3.2, 2.7, 2.3, 1.9, 1.5, 1.2, 1.0)
#: and their colours: none of them the red of a failure's line nor the orange of a fault's
CURVE_COLOURS = ("#1f77b4", "#2ca02c", "#9467bd", "#8c564b", "#17becf", "#e377c2", "#7f7f7f")
CURVE_DASHES: tuple[str | tuple[int, tuple[int, ...]], ...] = (
    "-", (0, (6, 2)), (0, (4, 2, 1, 2)), (0, (2, 2)), (0, (8, 3, 2, 3)), (0, (1, 2)), (0, (3, 3)))


@dataclass(frozen=True)
class Bar:
    """A leaf in one status from ``start_s`` for ``length_s`` of simulated time."""

    row: str
    start_s: float
    length_s: float
    status: str


def _pyplot() -> ModuleType:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(fig: Figure) -> bytes:
    from matplotlib.text import Text

    for text in fig.findobj(Text):  # names from files are text: a '$' must not start mathtext (it crashed)
        text.set_parse_math(False)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    _pyplot().close(fig)
    return buf.getvalue()


def gantt(rows: Sequence[str], bars: Sequence[Bar], failures: Sequence[tuple[float, str]],
          faults: Sequence[tuple[float, str]] = ()) -> bytes:
    """One row per leaf (tree order, top to bottom); a black tick where a leaf failed; a dashed orange line
    with its name where an injected fault fired. A bar is drawn at least :data:`MIN_BAR_FRACTION` of the run long:
    a leaf that finishes within a tick (10 ms of a 20 s run: a third of a pixel) would leave its row empty."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 0.42 * max(len(rows), 3) + 1.6), layout="constrained")
    index = {name: i for i, name in enumerate(rows)}
    ends = [bar.start_s + bar.length_s for bar in bars] + [t for t, _ in failures] + [t for t, _ in faults]
    starts = [bar.start_s for bar in bars]
    shortest = MIN_BAR_FRACTION * ((max(ends) - min(starts)) if starts and ends else 0.0)
    for status, colour in STATUS_COLOURS.items():
        spans: dict[int, list[tuple[float, float]]] = {}
        for bar in bars:
            if bar.status == status and bar.row in index:
                spans.setdefault(index[bar.row], []).append((bar.start_s, max(bar.length_s, shortest, 0.004)))
        for i, span in spans.items():
            ax.broken_barh(span, (i - 0.35, 0.7), facecolors=colour)
    for t, row in failures:
        if row in index:
            ax.plot([t], [index[row]], marker="v", color="black", markersize=7)
    for t, text in faults:  # the line across the rows, its name above the axes (over the bars it hid them)
        ax.axvline(t, color=FAULT_COLOUR, linestyle="--", linewidth=1.2)
        ax.annotate(f"fault: {text}", (t, 1.0), xycoords=("data", "axes fraction"), xytext=(0, 2),
                    textcoords="offset points", fontsize=7, color=FAULT_COLOUR, ha="center", va="bottom",
                    annotation_clip=False)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows)
    ax.invert_yaxis()
    ax.set_xlabel("simulated time (s)")
    ax.grid(axis="x", alpha=0.3)
    handles: list[Artist] = [plt.Rectangle((0, 0), 1, 1, color=c) for c in STATUS_COLOURS.values()]
    names = list(STATUS_COLOURS)
    if faults:
        handles.append(plt.Line2D([0], [0], color=FAULT_COLOUR, linestyle="--"))
        names.append("injected fault")
    # below the axis label, in space of its own (above the axes it covered the title and the faults' names)
    fig.legend(handles, names, loc="outside lower center", ncols=len(names), frameon=False)
    ax.set_title("Leaf statuses over simulated time (\u25bc: a FAILURE)", pad=24 if faults else 6)
    return _png(fig)


def series(t_s: NDArray[np.float64], values: NDArray[np.float64], labels: Sequence[str], title: str,
           ylabel: str, failures_s: Sequence[float] = (), faults: Sequence[tuple[float, str]] = ()) -> bytes:
    """Curves over simulated time (one per column of ``values``), a thin red dashed line where a leaf failed and
    a dashed orange line where an injected fault fired; the legend below the axis label, in space of its own."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 3.4), layout="constrained")
    values = values.reshape(len(t_s), -1)
    for j in range(values.shape[1]):
        ax.plot(t_s, values[:, j], label=labels[j] if j < len(labels) else str(j),
                color=CURVE_COLOURS[j % len(CURVE_COLOURS)], linewidth=CURVE_WIDTHS[min(j, len(CURVE_WIDTHS) - 1)],
                linestyle=CURVE_DASHES[j % len(CURVE_DASHES)])
    for t in failures_s:
        ax.axvline(t, color="#d64545", linestyle="--", linewidth=0.8)
    for t, _text in faults:
        ax.axvline(t, color=FAULT_COLOUR, linestyle="--", linewidth=1.6)
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    handles, names = ax.get_legend_handles_labels()
    if values.shape[1] <= 1:
        handles, names = [], []
    if failures_s:
        handles.append(plt.Line2D([0], [0], color="#d64545", linestyle="--", linewidth=0.8))
        names.append("a leaf failed")
    if faults:
        handles.append(plt.Line2D([0], [0], color=FAULT_COLOUR, linestyle="--", linewidth=1.6))
        names.append("injected fault")
    if handles:
        fig.legend(handles, names, fontsize=8, ncols=min(len(names), 5), loc="outside lower center",
                   frameon=False)
    return _png(fig)


def frame_with_boxes(rgb: NDArray[np.uint8], K: NDArray[np.float64] | None,
                     T_camera_base: ArrayLike | None,
                     boxes: Sequence[tuple[NDArray[np.float64], tuple[float, float, float], str]],
                     caption: str) -> bytes:
    """The camera frame with each detected box (pose in the base frame, size, label) projected onto it."""
    img = np.ascontiguousarray(rgb[:, :, ::-1]).copy()  # BGR for OpenCV
    if K is not None and T_camera_base is not None:
        for T_base_box, size, label in boxes:
            corners = box_corners_px(T_camera_base, K, T_base_box, size)
            if corners is None:
                continue
            px = corners.round().astype(int)
            for a, b in BOX_EDGES:
                cv2.line(img, tuple(px[a]), tuple(px[b]), (40, 220, 255), 1, cv2.LINE_AA)
            top = px[np.argmin(px[:, 1])]
            cv2.putText(img, label, (int(top[0]) - 20, int(top[1]) - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                        (40, 220, 255), 1, cv2.LINE_AA)
    cv2.putText(img, caption, (8, img.shape[0] - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 2, cv2.LINE_AA)
    cv2.putText(img, caption, (8, img.shape[0] - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise ValueError("OpenCV could not encode a report frame")
    return bytes(buf.tobytes())
