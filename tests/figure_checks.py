"""Looking at a rendered figure the way a reader does (issue 43, finding 9): where its legend, labels, bars and error
bars landed once drawn (their extents on the canvas), and which colours its pixels hold."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.container import BarContainer, ErrorbarContainer
from matplotlib.transforms import Bbox


def _agg(fig: Any) -> Any:
    """The figure's canvas, an Agg one (a ``Figure`` made without pyplot has a canvas that cannot draw)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig.canvas


def _legends(fig: Any) -> list[Any]:
    return [legend for ax in fig.axes if (legend := ax.get_legend()) is not None] + list(fig.legends)


def _marks(fig: Any, renderer: Any) -> Iterator[tuple[str, Bbox]]:
    """What a legend must never cover: every text (bar labels, tick labels, axis labels, titles), every bar and
    every error bar."""
    texts = [fig._suptitle] if getattr(fig, "_suptitle", None) is not None else []
    for ax in fig.axes:
        texts += [*ax.texts, ax.title, ax.xaxis.label, ax.yaxis.label]
        for axis in (ax.xaxis, ax.yaxis):  # the tick labels drawn: those of ticks inside the axis' view
            low, high = sorted(axis.get_view_interval())
            texts += [tick.label1 for tick in axis.get_major_ticks() if low - 1e-9 <= tick.get_loc() <= high + 1e-9]
        for container in ax.containers:
            if isinstance(container, ErrorbarContainer):
                _, caps, columns = container.lines
                for cap in caps:
                    yield "an error bar's cap", cap.get_window_extent(renderer)
                for column in columns:
                    for segment in column.get_segments():
                        points = column.get_transform().transform(np.asarray(segment))
                        yield "an error bar", Bbox([points.min(axis=0), points.max(axis=0)])
            elif isinstance(container, BarContainer):
                for patch in container.patches:
                    if patch.get_width() and patch.get_height():
                        yield f"a bar of {container.get_label()!r}", patch.get_window_extent(renderer)
    for text in texts:
        if text.get_visible() and text.get_text().strip():
            yield f"the text {text.get_text()!r}", text.get_window_extent(renderer)


def legend_overlaps(fig: Any) -> list[str]:
    """Every text, bar or error bar a legend of ``fig`` covers, once drawn (nothing: [])."""
    renderer = _agg(fig).get_renderer()
    problems = []
    for legend in _legends(fig):
        box = legend.get_window_extent(renderer).shrunk(0.98, 0.98)
        names = [t.get_text() for t in legend.get_texts()]
        for what, other in _marks(fig, renderer):
            if box.overlaps(other):
                problems.append(f"the legend {names} covers {what}")
    assert _legends(fig), "no legend to check"
    return problems


def pixels(fig: Any) -> np.ndarray:
    """The drawn canvas as RGB floats (rows top to bottom)."""
    return np.asarray(_agg(fig).buffer_rgba(), dtype=np.float64)[:, :, :3] / 255.0


def count_colour(image: np.ndarray, colour: str, tolerance: float = 0.06) -> int:
    """How many pixels hold ``colour`` (each channel within ``tolerance``)."""
    return int((np.abs(image - np.asarray(to_rgb(colour))) <= tolerance).all(axis=2).sum())


def texts_cut(fig: Any) -> list[str]:
    """Every text that runs past the figure's edge once drawn (a picture saved as it is cuts it off)."""
    renderer = _agg(fig).get_renderer()
    edge = fig.bbox
    cut = []
    for what, box in _marks(fig, renderer):
        if what.startswith("the text") and (box.x0 < edge.x0 - 1 or box.x1 > edge.x1 + 1 or box.y0 < edge.y0 - 1
                                            or box.y1 > edge.y1 + 1):
            cut.append(what)
    return cut
