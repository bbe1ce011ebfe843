"""BehaviorTree.CPP's substitution rules, compared with BT.CPP 4.10 itself: every case of ``rules/`` (a tree whose
leaves exist only in a TreeNodesModel, and a ``NAME.rules.json`` as BT.CPP's ``loadSubstitutionRuleFromJSON``
reads it) is run as a user runs it, ``bt-grasp tree run --dry --substitution-rules NAME.rules.json --json``, and
must end as BT.CPP ended it (``NAME.btcpp.json``, recorded by ``tools/btcpp_diff/record.py --cases``): the same
final status and root blackboard, and every status change of every node in the same order, halts included; with
the same tick for each when no rule has an ``async_delay`` (BT.CPP's delays count wall-clock time, bt_grasp's
simulated time: ``compare=order`` cases compare the order alone). A case BT.CPP refuses or stops on is exit 2
with one line."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli.main import main

from .test_corpus import directives
from .test_dry_run_cli import _blackboard, _expected_blackboard

RULES = Path(__file__).parent / "rules"
CASES = sorted(RULES.glob("*.xml"))
NAV2_CONTROLS = Path(__file__).resolve().parents[1] / "data" / "nav2" / "nav2_controls.py"


def run_case(tree: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str, dict[str, str]]:
    options = directives(tree.read_text())
    period_ms = max(int(options.get("period_ms", 10)), 1)
    args = ["tree", "run", str(tree), "--dry", "--json", "--substitution-rules", str(tree.with_suffix(".rules.json")),
            "--max-ticks", options.get("max_ticks", "20"), "--tick-hz", str(1000 / period_ms)]
    if "nodes_model" in options:
        args += ["--nodes-model", str(tree.parent / options["nodes_model"])]
    for item in filter(None, options.get("set", "").split(",")):
        args += ["--set", item]
    args += ["--leaves", str(NAV2_CONTROLS)] if options.get("nav2") == "1" else ["--no-plugins"]
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err, options


def test_every_case_is_recorded() -> None:
    assert len(CASES) >= 5
    assert [t.name for t in CASES if not t.with_suffix(".btcpp.json").exists()] == []
    assert [t.name for t in CASES if not t.with_suffix(".rules.json").exists()] == []


@pytest.mark.parametrize("tree", CASES, ids=[t.stem for t in CASES])
def test_substitution_rules_agree_with_btcpp(tree: Path, capsys: pytest.CaptureFixture[str]) -> None:
    expected: dict[str, Any] = json.loads(tree.with_suffix(".btcpp.json").read_text())
    code, out, err, options = run_case(tree, capsys)
    if expected.get("error"):
        assert code == 2, (out, err)
        lines = [line for line in err.strip().splitlines() if not line.startswith("bt-grasp: warning:")]
        assert len(lines) == 1 and re.match(r"^bt-grasp: error: \S+:\d+: ", lines[0]), err
        return
    run = json.loads(out)
    assert run["status"] == expected["status"], err
    assert _blackboard(run["blackboard"]) == _expected_blackboard(expected["blackboard"])
    if options.get("compare") == "order":
        got = [(t["path"], t["from"], t["to"]) for t in run["transitions"]]
        assert got == [tuple(t[1:]) for t in expected["transitions"]]
        return
    assert [[t["tick"], t["path"], t["from"], t["to"]] for t in run["transitions"]] == expected["transitions"]
    assert run["ticks"] == expected["ticks"]
    assert [t["status"] for t in run["walk"]] == expected["statuses"]
    assert [t["runs"] for t in run["walk"]] == expected["runs"]
