"""With ``SOURCE_DATE_EPOCH`` set, the same command with the same seed writes the same log, byte for byte
(issue 27: "a log must stay byte-identical for the same seed whatever the machine's speed"). Without it a log
carries its real start date and the tick loop's wall time, so two runs differ in those bytes only."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader

from bt_grasp.errors import InputError
from bt_grasp.recording.reproducible import log_epoch_ns, without_wall_clock

REPO = Path(__file__).resolve().parents[2]
EPOCH = "1767225600"  # 2026-01-01 00:00:00 UTC


@pytest.mark.parametrize(("value", "expected"), [
    (None, None), ("", None), ("  ", None), ("0", 0), (EPOCH, int(EPOCH) * 1_000_000_000),
])
def test_the_epoch_is_whole_seconds_or_unset(value: str | None, expected: int | None) -> None:
    assert log_epoch_ns({} if value is None else {"SOURCE_DATE_EPOCH": value}) == expected


@pytest.mark.parametrize("value", ["-5", "1.5", "1e9", "tomorrow", "253402300800", "9" * 400])
def test_a_bad_epoch_is_one_sentence(value: str) -> None:
    with pytest.raises(InputError, match=r"^SOURCE_DATE_EPOCH: expected whole seconds since 1970-01-01 UTC") as err:
        log_epoch_ns({"SOURCE_DATE_EPOCH": value})
    assert len(err.value.message) < 160  # a hostile value is cut, not echoed whole


def test_only_the_wall_clock_figures_are_nulled() -> None:
    result = {"success": True, "ticks": 733, "sim_time_s": 7.32, "wall_time_s": 1.25,
              "planning": {"calls": 1, "pose_calls": 1, "wall_s": 0.02}}
    assert without_wall_clock(result) == {"success": True, "ticks": 733, "sim_time_s": 7.32, "wall_time_s": None,
                                          "planning": {"calls": 1, "pose_calls": 1, "wall_s": None}}
    assert result["wall_time_s"] == 1.25  # the caller's result is left as it was


def _run(cwd: Path, epoch: str | None) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "SOURCE_DATE_EPOCH"}
    if epoch is not None:
        env["SOURCE_DATE_EPOCH"] = epoch
    cwd.mkdir()
    return subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "run", str(REPO / "trees/pick.xml"),
         "--scene", str(REPO / "scenes/tabletop.yaml"), "--log", "run.mcap", "--quiet"],
        capture_output=True, text=True, timeout=600, cwd=cwd, env={**env, "PYTHONPATH": str(REPO)})


def _result_and_meta(path: Path) -> tuple[dict[str, object], dict[str, str]]:
    with path.open("rb") as stream:
        reader = make_reader(stream)
        meta = next(dict(m.metadata) for m in reader.iter_metadata() if m.name == "bt_grasp.run")
    with path.open("rb") as stream:
        result = next(json.loads(msg.data) for _, _, msg in make_reader(stream).iter_messages(topics=["/run/result"]))
    return result, meta


@pytest.mark.sim
def test_the_same_command_writes_the_same_bytes(tmp_path: Path) -> None:
    first, second, dated = _run(tmp_path / "a", EPOCH), _run(tmp_path / "b", EPOCH), _run(tmp_path / "c", None)
    for proc in (first, second, dated):
        assert proc.returncode == 0, proc.stderr
    a, b, c = (tmp_path / d / "run.mcap" for d in "abc")
    assert a.read_bytes() == b.read_bytes()
    result, meta = _result_and_meta(a)
    assert meta["time_origin_ns"] == meta["start_unix_ns"] == str(int(EPOCH) * 1_000_000_000)
    assert result["success"] is True and result["wall_time_s"] is None
    assert result["planning"] == {"calls": 1, "pose_calls": 1, "wall_s": None}
    # the same run without the variable: the real date and the wall time, in those bytes only
    dated_result, dated_meta = _result_and_meta(c)
    assert a.read_bytes() != c.read_bytes()
    assert isinstance(dated_result["wall_time_s"], float) and dated_result["wall_time_s"] > 0
    assert int(dated_meta["time_origin_ns"]) > 1_700_000_000 * 10**9
    assert {k: v for k, v in dated_result.items() if k not in ("wall_time_s", "planning")} == \
        {k: v for k, v in result.items() if k not in ("wall_time_s", "planning")}


def test_a_bad_epoch_stops_the_run_before_it_starts(tmp_path: Path) -> None:
    proc = _run(tmp_path / "bad", "yesterday")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "bt-grasp: error: SOURCE_DATE_EPOCH: expected whole seconds since 1970-01-01 UTC (0 to 253402300799), "
        "got 'yesterday'"]
    assert not (tmp_path / "bad" / "run.mcap").exists()
