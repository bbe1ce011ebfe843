"""Tick overhead of the tree runtime: microseconds per node per tick for a flat tree of built-in nodes."""

from __future__ import annotations

import os
import platform
import time

from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.loader import load_tree_from_string


def bench_xml(n_nodes: int) -> str:
    """A ReactiveSequence of ``n_nodes - 1`` AlwaysSuccess leaves and a final Sleep that never finishes, so
    every tick visits every node and the tree stays RUNNING."""
    leaves = "".join("<AlwaysSuccess/>" for _ in range(max(n_nodes - 2, 0)))
    return (
        '<root BTCPP_format="4"><BehaviorTree ID="Bench"><ReactiveSequence>'
        f'{leaves}<Sleep msec="1000000000"/></ReactiveSequence></BehaviorTree></root>'
    )


def tick_overhead(n_nodes: int = 100, n_ticks: int = 1000) -> dict[str, object]:
    """Tick a ``n_nodes`` tree ``n_ticks`` times; report the cost per node per tick."""
    if n_nodes < 2 or n_ticks < 1:
        raise ValueError("tick_overhead needs n_nodes >= 2 and n_ticks >= 1")
    tree = load_tree_from_string(bench_xml(n_nodes), builtin_registry(), source="<bench>")
    tree.tick()  # warm-up
    start = time.perf_counter()
    for _ in range(n_ticks):
        tree.tick()
    elapsed = time.perf_counter() - start
    per_tick_us = elapsed / n_ticks * 1e6
    return {
        "n_nodes": n_nodes,
        "n_ticks": n_ticks,
        "total_s": elapsed,
        "us_per_tick": per_tick_us,
        "us_per_node_tick": per_tick_us / n_nodes,
        "python": platform.python_version(),
        "machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
        "cpus": os.cpu_count(),
    }
