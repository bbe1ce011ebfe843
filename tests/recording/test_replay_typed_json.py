"""Typed JSON fields (issue 24): replay --json printed the recorded seed as a string (``"seed": "7"``), since
MCAP metadata is text; it is a number now, and a log without a seed says null (the text view says '-')."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from recording_helpers import run_cli

from bt_grasp.recording.reader import open_log
from bt_grasp.recording.replay import summary


def test_replay_json_prints_the_seed_as_a_number(failed_run: tuple[Path, dict[str, Any]],
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(["replay", str(failed_run[0]), "--json"], capsys)
    assert code == 0, err
    data = json.loads(out)
    assert data["seed"] == 7 and isinstance(data["seed"], int)
    assert data["metadata"]["seed"] == "7"  # the metadata record itself stays as written in the log


@pytest.mark.parametrize(("text", "seed"), [("12", 12), ("not a seed", None), (None, None)])
def test_summary_seed_is_an_int_or_null(failed_run: tuple[Path, dict[str, Any]], text: str | None,
                                        seed: int | None) -> None:
    run = open_log(failed_run[0])
    if text is None:
        run.metadata.pop("seed", None)
    else:
        run.metadata["seed"] = text
    assert summary(run)["seed"] == seed
