"""Summary statistics of campaign results: success rates with Wilson score intervals, grouped."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

Z_95 = 1.959963984540054  # two-sided 95% normal quantile


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval for a binomial proportion (well-behaved at 0/n and n/n, unlike the Wald one)."""
    if n <= 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    # exact ends at 0/n and n/n, and always around p: rounding alone put p outside it (0/n: a lower end of
    # 1e-17 > 0; n/n: an upper end of 0.9999999999999999 < 1), which made negative error bars
    low = 0.0 if successes <= 0 else min(p, max(0.0, centre - half))
    high = 1.0 if successes >= n else max(p, min(1.0, centre + half))
    return (low, high)


@dataclass(frozen=True)
class Rate:
    group: tuple[str, ...]
    successes: int
    n: int

    @property
    def rate(self) -> float:
        return self.successes / self.n if self.n else 0.0

    @property
    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.successes, self.n)


def tree_label(row: Mapping[str, object]) -> str:
    tree = str(row["tree"])
    return tree.rsplit("/", 1)[-1].rsplit(".", 1)[0]


def group_value(row: Mapping[str, object], column: str) -> str:
    return tree_label(row) if column == "tree" else str(row[column])


def success_rates(rows: Iterable[Mapping[str, object]], by: Sequence[str]) -> list[Rate]:
    counts: dict[tuple[str, ...], list[int]] = {}
    for row in rows:
        key = tuple(group_value(row, c) for c in by)
        entry = counts.setdefault(key, [0, 0])
        entry[0] += bool(row["success"])
        entry[1] += 1
    return [Rate(k, s, n) for k, (s, n) in sorted(counts.items())]
