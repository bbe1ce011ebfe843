"""Issues 22 and 42: the fuzz suite, bounded, in the test suite. Every damaged MCAP log (bytes, records, contents),
results file, mesh and the files it names, URDF tree, collision-cache entry, ONNX model, control message, resident
request and crafted `--resim` log is answered by exit 0 or by exit 2 with one sentence naming the file; never a
traceback, a hang (10 s a case), a worker over 2 GiB, a file written outside the case's folder or a read of the
trap outside it. The long seeded run is `python tools/fuzz_inputs.py --cases 2000 --seed 0 --jobs 2` (its figure is
in docs/security.md)."""

from __future__ import annotations

import importlib.util
import sys
import time
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
    # a scene's loader may say a notice before its refusal; a re-simulation that did not reproduce exits 1
    notice = "object 'x': part.obj names texture file '/etc/x' outside its folder (/c): not read\n"
    assert fz.judge(2, notice + "bt-grasp: error: /c/s.yaml: bad\n", ("/c",), notices=True).ok
    assert not fz.judge(2, notice + "bt-grasp: error: /c/s.yaml: bad\n", ("/c",)).ok
    assert fz.judge(1, notice, ("/c",), ran=True).ok and not fz.judge(1, notice, ("/c",)).ok


def test_every_surface_is_in_the_table_and_the_ones_still_to_come_have_their_row() -> None:
    fz = _tool()
    assert {"log", "results", "mesh", "urdf", "cache", "model", "control", "resident", "resim"} <= {
        s for s, kinds in fz.SURFACES.items() if kinds}
    assert {"camera_recording", "cell_file", "twin_socket"} <= set(fz.SURFACES)
    assert fz.CASE_TIMEOUT_S == 10 and fz.CASE_MEMORY_BYTES == 2 << 30


def test_bounded_fuzz_run_has_no_failure_and_exercises_every_kind_and_view() -> None:
    fz = _tool()
    # 100 cases: every mutation kind of every surface at least once, every log view at least once, in 2 workers:
    # about 25 s on the 2-core machine at load 2, within 60 s under load
    start = time.monotonic()
    outcome = fz.fuzz(100, seed=6, jobs=2)
    seconds = time.monotonic() - start
    assert outcome.failures == [], "\n".join(outcome.failures)
    assert outcome.counts["read"] > 0 and outcome.counts["refused"] > 0, outcome.counts
    assert sum(outcome.counts.values()) == 100
    assert set(outcome.kinds) == set(fz.KINDS) and min(outcome.kinds.values()) >= 1, outcome.kinds
    assert set(fz.LOG_VIEWS) | {"eval report"} <= set(outcome.views), outcome.views
    assert seconds < 60, f"100 cases took {seconds:.0f} s"
