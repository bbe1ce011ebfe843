"""The campaign report's figures (matplotlib, no display): each function returns one figure's PNG bytes.

Counts are drawn on integer axes; a colour means one tree everywhere, and every figure that colours by tree
has a legend saying which; wall times leave out each worker's first episode, which pays the worker's warm-up
(the axis says how many were left out)."""

from __future__ import annotations

import io
from collections import Counter
from collections.abc import Sequence
from typing import TYPE_CHECKING, Literal

from bt_grasp.campaign.rows import ReportRow
from bt_grasp.campaign.stats import Rate, success_rates, tree_label

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axis import Axis
    from matplotlib.figure import Figure

GROUPS = ("tree", "scene", "fault_plan")
COLORS = ("#2b6cb0", "#dd6b20", "#38a169", "#805ad5", "#d53f8c", "#319795", "#718096")
#: a figure draws at most this many trees one by one (the others together, in grey) and this many groups, the
#: ones with most episodes (the tables list them all): a results file naming 20,000 trees took over ten minutes
#: and 4.8 GB to draw (found by the pre-review attack); and at most this many bars of a retry-count histogram
MAX_TREES_DRAWN = len(COLORS)
MAX_GROUPS_DRAWN = 40
MAX_RETRY_BARS = 40
OTHER_COLOR = "#a0aec0"


def _figure(width: float, height: float) -> Figure:
    import matplotlib

    matplotlib.use("Agg")  # no display; only files
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=100, layout="constrained")


def _png(fig: Figure) -> bytes:
    from matplotlib.text import Text

    for text in fig.findobj(Text):  # names from files are text: a '$' must not start mathtext (it crashed)
        text.set_parse_math(False)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


class _Trees:
    """The trees a figure draws one by one (those with most episodes, at most :data:`MAX_TREES_DRAWN`, the last
    place being "N other trees" when there are more) and which of them a row is drawn as."""

    def __init__(self, rows: Sequence[ReportRow]) -> None:
        counts = Counter(tree_label(r) for r in rows)
        if len(counts) <= MAX_TREES_DRAWN:
            self.kept = sorted(counts)
            self.other: str | None = None
        else:
            self.kept = sorted(t for t, _ in counts.most_common(MAX_TREES_DRAWN - 1))
            self.other = f"{len(counts) - len(self.kept)} other trees"
        self._kept = set(self.kept)
        self.labels = [*self.kept, *([self.other] if self.other is not None else [])]

    def of(self, row: ReportRow) -> str:
        label = tree_label(row)
        return label if label in self._kept or self.other is None else self.other

    def color(self, label: str) -> str:
        return COLORS[self.kept.index(label) % len(COLORS)] if label in self._kept else OTHER_COLOR


def _trees(rows: Sequence[ReportRow]) -> _Trees:
    return _Trees(rows)


def _integer_axis(axis: Axis) -> None:
    """Ticks only at whole numbers (counts of episodes or retries)."""
    from matplotlib.ticker import MaxNLocator

    axis.set_major_locator(MaxNLocator(integer=True))


def _tree_legend(fig: Figure, trees: _Trees) -> None:
    from matplotlib.patches import Patch

    _legend_below(fig, [Patch(facecolor=trees.color(t), label=t) for t in trees.labels])


def _legend_below(fig: Figure, handles: Sequence[Artist]) -> None:
    """The figure's legend below its axes, in space the layout keeps for it: never over a label, a bar or an error
    bar (inside the axes, "lower right" sat on the success figure's n/N labels and error bars)."""
    fig.legend(handles=list(handles), fontsize=8, loc="outside lower center", ncols=min(len(handles), 4),
               frameon=False)


def warm_up_rows(rows: Sequence[ReportRow]) -> set[int]:
    """Indexes of each worker's first episode (in the results file's order, the order they finished): it
    builds the worker's first world, so its wall time is not the steady one. Rows without a worker: none."""
    first: dict[str, int] = {}
    for index, row in enumerate(rows):
        worker = row.get("worker")
        if isinstance(worker, str) and worker not in first:
            first[worker] = index
    return set(first.values())


def success_by_group(rows: Sequence[ReportRow], title: str) -> bytes:
    rates = success_rates(rows, GROUPS)
    if len(rates) > MAX_GROUPS_DRAWN:
        most = set(sorted(range(len(rates)), key=lambda i: -rates[i].n)[:MAX_GROUPS_DRAWN])
        title += f" (the {MAX_GROUPS_DRAWN} of {len(rates)} groups with most episodes; the table lists all)"
        rates = [r for i, r in enumerate(rates) if i in most]
    fig = _figure(9, 0.9 + 0.38 * len(rates))
    ax = fig.add_subplot()
    trees = _trees(rows)
    ys = list(range(len(rates)))[::-1]
    for y, r in zip(ys, rates, strict=True):
        lo, hi = r.interval
        color = trees.color(r.group[0])
        ax.barh(y, r.rate, color=color, alpha=0.8, label=r.group[0])
        ax.errorbar(r.rate, y, xerr=[[r.rate - lo], [hi - r.rate]], fmt="none", ecolor="black", capsize=3)
        ax.text(1.01, y, f"{r.successes}/{r.n}", va="center", fontsize=8)
    _tree_legend(fig, trees)
    ax.set_yticks(ys, [" / ".join(r.group) for r in rates], fontsize=8)
    ax.set_xlim(0, 1.12)
    ax.set_xlabel("success rate (bars: 95% Wilson interval)")
    ax.set_title(title)
    ax.grid(axis="x", alpha=0.3)
    return _png(fig)


def failure_reasons(rows: Sequence[ReportRow]) -> bytes:
    failed = [r for r in rows if not r["success"]]
    trees = _trees(rows)
    keys = Counter(_failure_key(r) for r in failed)
    labels = [k for k, _ in keys.most_common(15)] or ["no failures"]
    fig = _figure(9, 1.2 + 0.35 * len(labels))
    ax = fig.add_subplot()
    left = [0] * len(labels)
    ys = list(range(len(labels)))[::-1]
    for tree in trees.labels:
        counts = Counter(_failure_key(r) for r in failed if trees.of(r) == tree)
        widths = [counts.get(k, 0) for k in labels]
        ax.barh(ys, widths, left=left, color=trees.color(tree), label=tree)
        left = [a + b for a, b in zip(left, widths, strict=True)]
    ax.set_yticks(ys, labels, fontsize=8)
    ax.set_xlabel("failed episodes")
    _integer_axis(ax.xaxis)
    ax.set_title("failure reasons (failing leaf)")
    _tree_legend(fig, trees)
    return _png(fig)


def _failure_key(row: ReportRow) -> str:
    return f"{row['failure_reason'] or '?'} ({row.get('failed_path') or row['failed_leaf'] or '-'})"


def time_distributions(rows: Sequence[ReportRow]) -> bytes:
    fig = _figure(10, 3.4)
    axes = fig.subplots(1, 2)
    warm = warm_up_rows(rows)
    steady = [r for i, r in enumerate(rows) if i not in warm]  # never all of them when every one was a warm-up
    left_out = len(rows) - len(steady)
    wall_label = "wall time per episode [s]" + (  # on three lines: on one it ran past the figure's edge
        f"\n(left out: {left_out}, each worker's first\nepisode, which pays its warm-up)" if left_out else "")
    column: Literal["sim_time_s", "episode_wall_s"]
    for ax, column, label, chosen in (
        (axes[0], "sim_time_s", "simulated time per episode [s]", rows),
        (axes[1], "episode_wall_s", wall_label, steady),
    ):
        trees = _trees(rows)
        ax.set_xlabel(label)
        if not chosen:  # a campaign so small that every episode was a worker's first: nothing steady to draw
            ax.text(0.5, 0.5, f"every episode ({len(rows)}) was its worker's first:\nno steady wall time to show",
                    transform=ax.transAxes, ha="center", va="center", fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            continue
        data = [[float(r[column]) for r in chosen if trees.of(r) == t] for t in trees.labels]
        ax.boxplot(data, orientation="horizontal", tick_labels=trees.labels)
        ax.grid(axis="x", alpha=0.3)
    fig.suptitle("time distributions")
    return _png(fig)


def retries(rows: Sequence[ReportRow]) -> bytes:
    fig = _figure(10, 3.2)
    axes = fig.subplots(1, 2)
    trees = _trees(rows)
    top = max([int(r["retries_total"]) for r in rows] + [1])
    step = -(-(top + 1) // MAX_RETRY_BARS)  # counts per bar: 1 unless an episode retried more than 39 times
    xs = list(range(0, top + 1, step))
    width = 0.8 * step / max(1, len(trees.labels))
    for i, tree in enumerate(trees.labels):
        counts = Counter(int(r["retries_total"]) // step * step for r in rows if trees.of(r) == tree)
        axes[0].bar(
            [x + (i - (len(trees.labels) - 1) / 2) * width for x in xs],  # around the whole number x
            [counts.get(x, 0) for x in xs],
            width,
            label=tree,
            color=trees.color(tree),
        )
    axes[0].set_xlabel("retries in the episode" + (f" (bars of {step})" if step > 1 else ""))
    axes[0].set_ylabel("episodes")
    _integer_axis(axes[0].xaxis)
    _integer_axis(axes[0].yaxis)
    _tree_legend(fig, trees)
    by_leaf: Counter[str] = Counter()
    for r in rows:
        by_leaf.update(r["retries"])
    leaves = [k for k, _ in by_leaf.most_common(10)] or ["none"]
    left = [0] * len(leaves)
    for tree in trees.labels:  # stacked by tree, in the trees' colours (the figure's legend)
        per_tree: Counter[str] = Counter()
        for r in rows:
            if trees.of(r) == tree:
                per_tree.update(r["retries"])
        widths = [per_tree.get(k, 0) for k in leaves[::-1]]
        axes[1].barh(leaves[::-1], widths, left=left, color=trees.color(tree), label=tree)
        left = [a + b for a, b in zip(left, widths, strict=True)]
    _integer_axis(axes[1].xaxis)
    axes[1].set_xlabel("retries, all episodes")
    axes[1].set_title("retried leaves", fontsize=9)
    fig.suptitle("retries")
    return _png(fig)


def comparison(a: Sequence[Rate], b: Sequence[Rate], names: tuple[str, str]) -> bytes:
    by_a, by_b = {r.group: r for r in a}, {r.group: r for r in b}
    groups = sorted(by_a.keys() | by_b.keys())
    title = f"{names[0]} vs {names[1]}"
    if len(groups) > MAX_GROUPS_DRAWN:
        def episodes(g: tuple[str, ...]) -> int:
            return sum(rates[g].n for rates in (by_a, by_b) if g in rates)

        title += f" (the {MAX_GROUPS_DRAWN} of {len(groups)} groups with most episodes; the tables list all)"
        groups = sorted(sorted(groups, key=lambda g: -episodes(g))[:MAX_GROUPS_DRAWN])
    fig = _figure(9, 1.0 + 0.55 * len(groups))
    ax = fig.add_subplot()
    for offset, rates, name, color in ((0.2, by_a, names[0], COLORS[0]), (-0.2, by_b, names[1], COLORS[1])):
        ys, xs, lows, highs = [], [], [], []
        for y, g in enumerate(reversed(groups)):
            if g in rates:
                r = rates[g]
                lo, hi = r.interval
                ys.append(y + offset)
                xs.append(r.rate)
                lows.append(r.rate - lo)
                highs.append(hi - r.rate)
        ax.barh(ys, xs, height=0.38, color=color, alpha=0.8, label=name)
        ax.errorbar(xs, ys, xerr=[lows, highs], fmt="none", ecolor="black", capsize=2)
    from matplotlib.patches import Patch
    ax.set_yticks(range(len(groups)), [" / ".join(g) for g in reversed(groups)], fontsize=8)
    ax.set_xlim(0, 1.05)
    ax.set_xlabel("success rate (bars: 95% Wilson interval)")
    ax.set_title(title)
    _legend_below(fig, [Patch(facecolor=c, alpha=0.8, label=n) for n, c in zip(names, COLORS, strict=False)])
    ax.grid(axis="x", alpha=0.3)
    return _png(fig)
