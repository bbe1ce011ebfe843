"""The user's path, compared with BehaviorTree.CPP: every corpus tree made of built-ins and other projects'
nodes (no driver test leaf) is run with ``bt-grasp tree run --dry --leaves standins.py --json``, the stand-ins
loaded from a plugin file as a user loads theirs, and must end as BT.CPP 4.10 ended it (the recorded
``NAME.btcpp.json``): the same final status and root blackboard, and for trees without wall-clock timers the
same root status at every tick and the same number of root executions (wake-ups) in each tick. A tree BT.CPP
refuses or stops on is exit 2 with one line naming the file and line."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli.main import main

from .test_corpus import CORPUS, TREES, directives

STANDINS = Path(__file__).parent / "standins.py"
DRIVER_LEAVES = re.compile(r"<(TestAction|TestCondition|Counter|WriteReal|EchoText)\b|ID=\"(RED|GREEN|BLUE)\"")
ENUMS = re.compile(r"\b(RED|GREEN|BLUE)\b")
FOREIGN = [t for t in TREES if not DRIVER_LEAVES.search(t.read_text()) and not ENUMS.search(t.read_text())]


def _expected_blackboard(recorded: dict[str, Any]) -> dict[str, Any]:
    """BT.CPP's typed blackboard as ``tree run --json`` prints it: scalars as JSON values, empty entries left
    out, other objects by the presence of their key only."""
    out: dict[str, Any] = {}
    for key, typed in recorded.items():
        if typed["type"] == "empty":
            continue
        out[key] = typed.get("value") if typed["type"] != "other" else "<object>"
    return out


def _blackboard(printed: dict[str, Any]) -> dict[str, Any]:
    def plain(value: Any) -> Any:
        return "<object>" if isinstance(value, str) and value.startswith("<") and " object at " in value else value

    return {k: plain(v) for k, v in printed.items()}


def test_the_user_path_covers_the_foreign_trees() -> None:
    assert len([t for t in FOREIGN if t.name.startswith("ext_")]) >= 30


@pytest.mark.parametrize("tree", FOREIGN, ids=[t.stem for t in FOREIGN])
def test_dry_run_with_user_stand_ins_agrees_with_btcpp(tree: Path, capsys: pytest.CaptureFixture[str]) -> None:
    expected = json.loads(tree.with_suffix(".btcpp.json").read_text())
    options = directives(tree.read_text())
    period_ms = max(int(options.get("period_ms", 10)), 1)
    args = ["tree", "run", str(tree), "--dry", "--leaves", str(STANDINS), "--json",
            "--max-ticks", options.get("max_ticks", "20"), "--tick-hz", str(1000 / period_ms)]
    code = main(args)
    out, err = capsys.readouterr()
    if expected.get("error"):
        assert code == 2, (out, err)
        lines = [line for line in err.strip().splitlines() if line.strip()]
        assert len(lines) == 1 and re.match(rf"^(bt-grasp: error: )?{re.escape(str(tree))}:\d+: ", lines[0]), err
        return
    run = json.loads(out)
    assert run["status"] == expected["status"]
    if expected["status"] != "RUNNING":  # tree run halts an unfinished tree at the end, as BT.CPP's ~Tree does;
        # the driver prints the blackboard before that (the halts' own writes would differ)
        assert _blackboard(run["blackboard"]) == _expected_blackboard(expected["blackboard"])
    if options.get("compare") == "final":
        return
    if expected["status"] == "SKIPPED":  # the driver ticks on; tree run stops as BT.CPP's tickWhileRunning does
        expected = {**expected, "ticks": 1, "statuses": expected["statuses"][:1], "runs": expected["runs"][:1]}
    assert run["ticks"] == expected["ticks"]
    assert [t["status"] for t in run["walk"]] == expected["statuses"]
    assert [t["runs"] for t in run["walk"]] == expected["runs"]
    if expected["status"] in ("SUCCESS", "FAILURE"):  # the walk as BT.CPP's StatusChangeLogger saw it
        assert [[t["tick"], t["path"], t["from"], t["to"]] for t in run["transitions"]] == expected["transitions"]


def test_corpus_folder_is_the_one_the_tests_read() -> None:
    assert CORPUS.is_dir() and STANDINS.is_file()
