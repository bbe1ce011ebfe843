"""Differential conformance: every corpus tree, run through bt_grasp, matches what BehaviorTree.CPP 4.10.0
itself did with it (recorded by tools/btcpp_diff/record.py into NAME.btcpp.json next to NAME.xml).

Compared: the final status, the root blackboard (typed: int, real, str, bool), and for trees without
wall-clock timers also the tick count, the root status of every tick, how many times each tick executed
the root (wake-up re-runs), every node's status after each tick, the nodes' full paths, each test
leaf's ticks, starts and halts, and every status change of every node in order with its tick, halts to IDLE
included (what BT.CPP's StatusChangeLogger, and so StdCoutLogger and Groot2's log, receive). Errors compare by
phase (refused at load, or failed while ticking).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest

from .twin import run_tree

CORPUS = Path(__file__).parent / "corpus"
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools" / "btcpp_diff"))
from record import corpus_trees, directives  # noqa: E402

TREES = corpus_trees(CORPUS)
ALWAYS = ("status", "blackboard")
TICKED = ("ticks", "statuses", "runs", "nodes", "paths", "leaves", "transitions")


def _phase(result: dict[str, Any]) -> str | None:
    error = result.get("error")
    return error["phase"] if error else None


def test_the_corpus_is_large_and_recorded() -> None:
    assert len(TREES) >= 80
    missing = [t.name for t in TREES if not t.with_suffix(".btcpp.json").exists()]
    assert missing == []


@pytest.mark.parametrize("tree", TREES, ids=[t.stem for t in TREES])
def test_tree_agrees_with_btcpp(tree: Path) -> None:
    expected = json.loads(tree.with_suffix(".btcpp.json").read_text())
    options = directives(tree.read_text())
    got = run_tree(tree.resolve(), int(options.get("max_ticks", 20)), int(options.get("period_ms", 0)))
    assert _phase(got) == _phase(expected), (got.get("error"), expected.get("error"))
    if _phase(expected) == "load":
        return
    fields = ALWAYS if options.get("compare") == "final" else ALWAYS + TICKED
    differences = {
        k: {"bt_grasp": got.get(k), "btcpp": expected.get(k)} for k in fields if got.get(k) != expected.get(k)
    }
    assert differences == {}
