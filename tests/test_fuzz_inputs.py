"""Issue 22: the log/results fuzz suite, bounded, in the test suite. Every damaged MCAP log (bytes, records,
contents) and results file is answered by exit 0 or by exit 2 with one sentence naming the file; never a
traceback, a hang, an exhausted worker or a file written outside the case's folder. The long seeded run is
`python tools/fuzz_inputs.py --cases 2000 --seed 0` (its figure is in docs/security.md)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("fuzz_inputs", REPO / "tools" / "fuzz_inputs.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_inputs"] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def test_the_judge_fails_what_the_suite_is_for() -> None:
    fz = _tool()
    assert fz.judge(0, "", "a.mcap").ok
    assert fz.judge(2, "error: /x/a.mcap: cut off\n", "a.mcap").detail == "refused"
    assert not fz.judge(-1, "Traceback: KeyError: 'tick'", "a.mcap").ok
    assert not fz.judge(2, "a warning about a.mcap\nerror: a.mcap: cut off\n", "a.mcap").ok  # two sentences
    assert not fz.judge(2, "error: cut off\n", "a.mcap").ok  # the file is not named
    assert not fz.judge(1, "error: a.mcap: cut off\n", "a.mcap").ok  # another exit code


def test_bounded_fuzz_run_has_no_failure_and_exercises_every_kind_and_view() -> None:
    fz = _tool()
    n = len(fz.KINDS)  # every mutation kind once, every log view at least once: about 45 s on a loaded 2-core machine
    # seed 6: with the message-shape checks of bt_grasp/recording/validate.py turned off, its wrong-schema log
    # case crashes (1 failure); with the results-row checks turned off, 2 results cases crash (both tried)
    outcome = fz.fuzz(n, seed=6)
    assert outcome.failures == [], "\n".join(outcome.failures)
    assert outcome.counts["read"] > 0 and outcome.counts["refused"] > 0, outcome.counts
    assert sum(outcome.counts.values()) == n
    assert set(outcome.kinds) == set(fz.KINDS) and min(outcome.kinds.values()) == 1, outcome.kinds
    assert set(outcome.views) == {*fz.LOG_VIEWS, "eval report"}, outcome.views
