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
    with its name where an injected fault fired."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 0.42 * max(len(rows), 3) + 1.2))
    index = {name: i for i, name in enumerate(rows)}
    for status, colour in STATUS_COLOURS.items():
        spans: dict[int, list[tuple[float, float]]] = {}
        for bar in bars:
            if bar.status == status and bar.row in index:
                spans.setdefault(index[bar.row], []).append((bar.start_s, max(bar.length_s, 0.004)))
        for i, span in spans.items():
            ax.broken_barh(span, (i - 0.35, 0.7), facecolors=colour)
    for t, row in failures:
        if row in index:
            ax.plot([t], [index[row]], marker="v", color="black", markersize=7)
    for t, text in faults:
        ax.axvline(t, color=FAULT_COLOUR, linestyle="--", linewidth=1.2)
        ax.annotate(f"fault: {text}", (t, -0.6), rotation=90, fontsize=7, color=FAULT_COLOUR, va="top",
                    ha="right", annotation_clip=False)
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
    ax.legend(handles, names, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=len(names), frameon=False)
    ax.set_title("Leaf statuses over simulated time (\u25bc: a FAILURE)", pad=24)
    return _png(fig)


def series(t_s: NDArray[np.float64], values: NDArray[np.float64], labels: Sequence[str], title: str,
           ylabel: str, failures_s: Sequence[float] = ()) -> bytes:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 3.2))
    values = values.reshape(len(t_s), -1)
    for j in range(values.shape[1]):
        ax.plot(t_s, values[:, j], label=labels[j] if j < len(labels) else str(j), linewidth=1.3)
    for t in failures_s:
        ax.axvline(t, color="#d64545", linestyle="--", linewidth=0.8)
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    if values.shape[1] > 1:
        ax.legend(fontsize=8, ncol=min(values.shape[1], 6), loc="upper center", bbox_to_anchor=(0.5, -0.22),
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
